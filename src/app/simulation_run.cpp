// The driver (paper Algorithm 1 with AMRC, grid sequencing and output
// between steps) and one time step with what a run counts of it.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>

#include "amrc/sequence.hpp"
#include "app/memory.hpp"
#include "app/signals.hpp"
#include "app/simulation.hpp"
#include "base/error.hpp"
#include "decomp/collective.hpp"

namespace drape {

namespace {

// Test hook (fault injection): DRAPE_FAULT_NAN_STEP=k poisons one free
// particle's position before step k, so the numerical-failure path (exit 3,
// the last checkpoint kept) can be exercised on purpose.
int fault_step() {
  const char* v = std::getenv("DRAPE_FAULT_NAN_STEP");
  return v ? std::atoi(v) : 0;
}

// Test hook: DRAPE_FAULT_INTERNAL_RANK=r makes rank r alone throw an internal
// error before the step DRAPE_FAULT_NAN_STEP names, the way a bug on one
// rank would, so that the others are seen not to wait for it.
int fault_internal_rank() {
  const char* v = std::getenv("DRAPE_FAULT_INTERNAL_RANK");
  return v ? std::atoi(v) : -1;
}

void inject_nan(Cloth& c, const ActiveLists& lists) {
  for (int64_t p : lists.particles.items)
    if (c.free(p)) {
      c.x1_at(p)[2] = std::numeric_limits<double>::quiet_NaN();  // the prediction carries it
      return;
    }
}

void add_step(RunCounters& n, const StepStats& st, int64_t active) {
  n.iterations += st.iterations;
  n.particle_iterations += st.iterations * active;
  n.evaluations += st.evaluations;
  n.newton_iterations += st.newton_iterations;
  n.projections += st.projections;
  n.max_step_iterations = std::max<int64_t>(n.max_step_iterations, st.iterations);
  n.unconverged += st.converged ? 0 : 1;
  n.dt_min = std::min(n.dt_min, st.dt);
  n.dt_max = std::max(n.dt_max, st.dt);
}

double norm(const double v[3]) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

}  // namespace

int Simulation::run() {
  // Files are open collectively from start() on: an error that struck this
  // rank alone must end every rank before unwinding reaches a collective
  // close (the others would wait in it, or in the step's exchange, forever).
  try {
    start();
    while (cloth.step < scene.solver.steps) {
      const StepStats st = step();
      if (st.stopped) break;
      const Ending end = ending(st);
      if (sum_.at_rest && sequence_level_ > scene.amrc.last_level && !end.last && finer_mesh_fits()) next_stage();
      if (!end.last && !sum_.at_rest && due(scene.output.every, st.step)) write();
      if (scene.amrc.enabled && st.step % scene.amrc.every == 0) adapt();
      if (due(scene.output.checkpoint_every, st.step)) checkpoint();
      if (sum_.at_rest || end.reached || stop_now()) break;
    }
    finish();
    return 0;
  } catch (const InputError&) {
    throw;
  } catch (const NumericalError&) {
    throw;
  } catch (const CollectiveError&) {
    throw;
  } catch (const std::exception& e) {
    if (ranks_ == 1) throw;
    end_all_ranks(comm_, e.what());
  }
}

StepStats Simulation::step() {
  inject_faults();
  const auto wall0 = clock::now();
  const int64_t cpu0 = process_cpu_microseconds();
  const StepStats st =
      loop->step(tm_, [&](int it, double cost) { progress_->iteration(cloth.step + 1, it, cost); });
  if (st.stopped) return st;
  account(st, wall0, cpu0);
  if (cloth.time < ease_until_) relax_eased_edges(cloth, loop->evaluator(), kEaseRate, st.dt);
  progress_->step(st, amrc ? sum_.active_final : -1);
  return st;
}

StepStats Simulation::advance(int n) {
  StepStats st = step();
  for (int k = 1; k < n; ++k) st = step();
  return st;
}

void Simulation::inject_faults() {
  if (poison_ != cloth.step + 1) return;
  if (poison_rank_ < 0) inject_nan(cloth, lists);
  if (poison_rank_ == rank_) throw std::logic_error("fault injected on purpose (DRAPE_FAULT_INTERNAL_RANK)");
}

void Simulation::account(const StepStats& st, clock::time_point wall0, int64_t cpu0) {
  if (!sum_.stages.empty())
    sum_.stages.back().add(st, std::chrono::duration<double>(clock::now() - wall0).count(),
                           1e-6 * double(process_cpu_microseconds() - cpu0));
  add_step(sum_.counters, st, sum_.active_final);
  sum_.last = st;
}

// The speed below which a step is calm: rest_speed, or with friction the
// creep its ramp lets a held particle make, a few slips eps a step (lagged
// friction re-anchors at each step's start; measured about 2 eps a step on
// the box drape): at Jacobi's 0.2 ms steps that creep alone is 10 mm/s.
double calm_speed(const SolverSpec& sv, const Contact& c, double dt) {
  const double creep = c.has_friction() && dt > 0 ? kCreepSlips * c.slip / dt : 0.0;
  return std::max(sv.rest_speed, creep);
}

// The run ends at solver.steps, at solver.end_time, or at rest: three calm
// steps, spanning at least the time a cloth let go from rest takes to pass
// the calm speed twice over (the top of a fall is not rest).
Simulation::Ending Simulation::ending(const StepStats& st) {
  const SolverSpec& sv = scene.solver;
  const bool easing = cloth.time < ease_until_;
  Ending end;
  end.reached = sv.end_time > 0 && cloth.time >= sv.end_time;
  end.last = st.step == sv.steps || end.reached;
  const double calm = calm_speed(sv, model.contact, st.dt);
  sum_.counters.calm = (sv.rest_speed > 0 && st.max_speed < calm && !easing) ? sum_.counters.calm + 1 : 0;
  const double g = norm(model.gravity);
  const double calm_span = g > 0 ? 2 * calm / (g * st.dt) : 0;
  sum_.at_rest = sum_.counters.calm >= std::max(3.0, std::ceil(calm_span));
  return end;
}

void Simulation::arm_faults() {
  poison_ = fault_step();
  poison_rank_ = fault_internal_rank();  // -1: the step is poisoned with a NaN
}

// Stop requests are polled every iteration and agreed on by all ranks, so
// that every rank stops at the same iteration: a signal on any rank, or
// the wall-clock budget on rank 0's clock.
bool Simulation::stop_now() {
  if (stop_code_) return true;
  const double elapsed = std::chrono::duration<double>(clock::now() - t0_).count();
  const bool budget = rank_ == 0 && scene.solver.wall_limit > 0 && elapsed > scene.solver.wall_limit;
  stop_code_ = max_over_ranks(comm_, 2 * stop_signal() + (budget ? 1 : 0));
  return stop_code_ != 0;
}

}  // namespace drape
