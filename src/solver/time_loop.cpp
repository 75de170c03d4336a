#include "solver/time_loop.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "base/error.hpp"
#include "solver/fit.hpp"
#include "solver/kernels.hpp"
#include "solver/loops.hpp"

namespace drape {

TimeLoop::TimeLoop(Cloth& cloth, Model& model, const ActiveLists& lists, const Tiling& tiling,
                   const LoopPolicy& policy, const Reducer& red, const SolverSpec& spec,
                   const Halo& halo)
    : c_(cloth), m_(model), lists_(lists), red_(red), halo_(halo), spec_(spec),
      ev_(cloth, model, lists, tiling, policy, red, halo), cg_(cloth, lists, tiling, red),
      newton_(cloth, cg_, spec.preconditioner) {
  fit_saved(true);
  if (spec.method == SolverMethod::Newton && spec.band_active_set) ev_.track_branches(true);
  if (spec.method != SolverMethod::Newton) ev_.hold_stiffness(false);  // the nonlinear CG reads none of K
  newton_.set_divided(spec.multigrid_divided);
  free_ = red.sum_i64(lists.particles.size());
}

// Sized by this rank's unknowns (the lists'), as the evaluator's arrays.
void TimeLoop::fit_saved(bool exact) {
  const size_t need = size_t(cg_.unknowns_below(c_.layout.size()));
  fit(z_saved_, need, c_.z.size(), exact, 0.0);
}

void TimeLoop::memory(MemoryTable& t) const {
  ev_.memory(t);
  cg_.memory(t);
  newton_.memory(t);
  t.add("TimeLoop", "saved unknowns (a step's retry)", z_saved_);
  t.add("TimeLoop", "the halo's history slots", hist_send_.capacity() * 4 + hist_recv_.capacity() * 4);
}

void TimeLoop::freeze_bend_axes() { ev_.freeze_bend_axes(c_.x1.data(), c_.slots()); }

// Packed in the compact numbering of all the unknowns (Minimizer's, tile by
// tile): a rank holds its own only.
void TimeLoop::save_unknowns() {
  fit_saved(false);  // the lists changed without mesh_changed (tests): grows here
  const double* z = c_.z.data();
  double* s = z_saved_.data();
  cg_.for_each_unknown(c_.layout.size(), [&](int64_t c, int64_t k) { s[c] = z[k]; });
}

void TimeLoop::restore_unknowns() {
  double* z = c_.z.data();
  const double* s = z_saved_.data();
  cg_.for_each_unknown(c_.layout.size(), [&](int64_t c, int64_t k) { z[k] = s[c]; });
}

// x (x1 or x2) at its ghosts from their owners. Held in slots (several
// ranks), through the halo plan's particles' slots.
void TimeLoop::exchange_history(double* x) {
  if (c_.slot_of.empty()) {
    halo_.exchange(x, Halo::kPositions);
    return;
  }
  if (hist_plan_ != halo_.plan_version() || hist_held_ != c_.held_version) map_history_halo();
  halo_.exchange_at(x, hist_send_.data(), hist_recv_.data());
}

// The plan's visitors capture one reference each: a std::function holds
// that without allocating.
void TimeLoop::map_history_halo() {
  hist_plan_ = halo_.plan_version();
  hist_held_ = c_.held_version;
  int64_t counts[2] = {0, 0};  // received, sent
  halo_.plan([&counts](int64_t, bool send) { ++counts[send]; });
  fit(hist_send_, size_t(counts[1]), size_t(counts[1]), false, int32_t(-1));
  fit(hist_recv_, size_t(counts[0]), size_t(counts[0]), false, int32_t(-1));
  struct {
    const Cloth& c;
    int32_t* at[2];  // the next receive's, send's entry
    void operator()(int64_t id, bool send) { *at[send]++ = c.holds(id) ? int32_t(c.slot(id)) : -1; }
  } place{c_, {hist_recv_.data(), hist_send_.data()}};
  halo_.plan([&place](int64_t id, bool send) { place(id, send); });
}

void TimeLoop::refresh_ghosts(bool history) {
  halo_.exchange(c_.z.data(), Halo::kAll, c_.layout, c_.slots());
  ev_.interpolate_hanging(c_.z.data());
  if (!history) return;
  for (std::vector<double>* x : {&c_.x1, &c_.x2}) {
    exchange_history(x->data());
    ev_.interpolate_hanging(x->data(), c_.slots());
  }
}

// The first guess of a step: the history moved on with its velocity, and
// with `fall` 1 gravity's free fall added (exact for a falling cloth), with 0
// not (exact for a cloth at rest).
void TimeLoop::predict(double fall) {
  const double ratio = c_.dt / c_.dt_prev;
  const double reach = fall / m_.accel_coeff();  // x moved by g/ca gives a = g
  double* x = c_.x();
  const ActiveList& L = lists_.particles;
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < L.size(); ++k) {
    const int64_t p = L.items[k];
    const double *x1 = c_.x1_at(p), *x2 = c_.x2_at(p);
    for (int i = 0; i < 3; ++i) x[3 * p + i] = x1[i] + ratio * (x1[i] - x2[i]) + m_.gravity[i] * reach;
  }
}

// Contact CFL: how far (m) the smooth prediction carries any particle past
// the contact margin. Halving dt until this is small lets contact engage over
// several steps instead of one violent one.
double TimeLoop::margin_overshoot() const {
  const Obstacle& ob = m_.contact.obstacle;
  if (ob.shape == ObstacleShape::None && !ob.floor) return 0;
  const double* x = c_.x();
  const ActiveList& L = lists_.particles;
  double worst = 0;
#pragma omp parallel for schedule(static) reduction(max : worst)
  for (int64_t k = 0; k < L.size(); ++k) {
    const int64_t p = L.items[k];
    const double target = std::min(m_.contact.thickness, clearance(ob, c_.x1_at(p)));
    worst = std::max(worst, target - clearance(ob, x + 3 * p));
  }
  return red_.max(worst);
}

// Where the cloth lies at rest on an obstacle the fall's guess presses
// g dt^2 into the contact layer's penalty and stretches the edges that hold
// the hanging sides: Newton's first residuals then run to a hundred particle
// weights a particle. Which guess is nearer is read from the cost, a
// fixed-order sum (the same choice on any ranks and threads). Counts its
// evaluations and the guess taken in st; *settled is the cost the evaluator
// settled last where that was at the guess taken (Newton then starts from
// it), else null.
void TimeLoop::choose_prediction(Timers& tm, StepStats& st, const CostTerms** settled) {
  *settled = nullptr;
  st.rest_guess = false;
  if (spec_.prediction == Prediction::Fall) return;
  double fall = 0;
  if (spec_.prediction == Prediction::Cheaper) {
    ScopedPhase ph(tm, kGradient);
    fall = ev_.settled_cost(c_.z.data()).total();
    ++st.evaluations;
  }
  predict(0.0);
  stop_all_at_margin();
  st.rest_guess = true;
  if (spec_.prediction == Prediction::Rest) return;
  if (ev_.branches().enabled()) ev_.branches().at_z();  // where Newton's first evaluation notes them
  {
    ScopedPhase ph(tm, kGradient);
    guess_cost_ = ev_.settled_cost(c_.z.data());
    ++st.evaluations;
  }
  const double rest = guess_cost_.total();
  if (std::isfinite(fall) && !(rest <= fall)) {  // the fall, unless it overflowed
    predict(1.0);
    stop_all_at_margin();
    st.rest_guess = false;
  } else {
    *settled = &guess_cost_;
  }
}

void TimeLoop::stop_all_at_margin() {
  const ActiveList& L = lists_.particles;
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < L.size(); ++k) stop_at_margin(L.items[k]);
}

// A fast particle would be predicted deep inside an obstacle, where the
// penalty cost is enormous and CG stalls: shorten its predicted move so it
// stops where it meets the contact margin (bisection on the move's length;
// projecting instead could put two particles on one point at an edge).
void TimeLoop::stop_at_margin(int64_t p) {
  const Obstacle& ob = m_.contact.obstacle;
  double* x = c_.x() + 3 * p;
  const double* x1 = c_.x1_at(p);
  const double target = std::min(m_.contact.thickness, clearance(ob, x1));
  if (clearance(ob, x) >= target) return;
  const double move[3] = {x[0] - x1[0], x[1] - x1[1], x[2] - x1[2]};
  double lo = 0, hi = 1, y[3];
  for (int it = 0; it < 30; ++it) {
    const double t = 0.5 * (lo + hi);
    for (int k = 0; k < 3; ++k) y[k] = x1[k] + t * move[k];
    (clearance(ob, y) >= target ? lo : hi) = t;
  }
  for (int k = 0; k < 3; ++k) x[k] = x1[k] + lo * move[k];
}

void TimeLoop::check_finite(const StepStats& st) const {
  if (std::isfinite(st.cost.total())) return;
  const Grid& g = c_.grid;
  const std::vector<double>& rho = ev_.residual();
  const ActiveList& L = lists_.particles;
  for (int64_t r = 0; r < L.size(); ++r)
    for (int k = 0; k < 3; ++k)
      if (const int64_t p = L.items[r]; !std::isfinite(c_.z[3 * p + k]) || !std::isfinite(rho[3 * r + k])) {
        std::ostringstream os;
        os << "numerical failure at step " << st.step << ", iteration " << st.iterations
           << ": non-finite position or force residual at particle (" << g.i_of(p) << ", "
           << g.j_of(p) << ")";
        throw NumericalError(os.str());
      }
  std::ostringstream os;
  os << "numerical failure at step " << st.step << ", iteration " << st.iterations
     << ": the cost is not finite (an element force overflowed)";
  throw NumericalError(os.str());
}

void TimeLoop::accept(StepStats& st) {
  const double damp = spec_.damping;
  double* x = c_.x();
  const ActiveList& L = lists_.particles;
  double vmax = 0;
  int64_t pushed = 0;
  const Obstacle& ob = m_.contact.obstacle;
#pragma omp parallel for schedule(static) reduction(max : vmax) reduction(+ : pushed)
  for (int64_t k = 0; k < L.size(); ++k) {
    const int64_t p = L.items[k];
    double* xp = x + 3 * p;
    double dx[3];
    double *x1 = c_.x1_at(p), *x2 = c_.x2_at(p);
    for (int i = 0; i < 3; ++i) dx[i] = xp[i] - x1[i];
    // Safety net: a particle that ended inside an obstacle is put back on its
    // surface, and remembers no speed into it nor any from the push.
    if (penetration(ob, xp) > 0) {
      settle_on_surface(ob, xp, dx);
      ++pushed;
    }
    double v2 = 0;
    for (int i = 0; i < 3; ++i) {
      const int64_t u = 3 * p + i;
      v2 += dx[i] * dx[i];
      x2[i] = x[u] - (1.0 - damp) * dx[i];  // damping shortens the remembered velocity
      x1[i] = x[u];
    }
    vmax = std::max(vmax, std::sqrt(v2) / c_.dt);
  }
  ev_.interpolate_hanging(c_.x1.data(), c_.slots());  // hanging particles follow their ends
  ev_.interpolate_hanging(c_.x2.data(), c_.slots());
  st.max_speed = red_.max(vmax);
  st.projections = red_.sum_i64(pushed);
}

// Jacobi's (and nonlinear CG's) iterations grow with dt·c/h: keeping them
// within [max/8, max/2] keeps a step's cost bounded. The multigrid's linear
// count is nearly flat in dt, so it cannot choose dt; the Newton iterations,
// which grow with dt (the prediction's error), do: dt grows while a step
// takes at most newton_target of them and shrinks above 1.5 times that, on a
// retried step, or when the linear iterations pass max/2.
double next_time_step(const SolverSpec& spec, double dt, const StepEffort& e) {
  const int max = spec.max_iterations;
  double next = dt;
  if (spec.method == SolverMethod::Newton && spec.preconditioner == Preconditioner::Multigrid) {
    const int target = spec.newton_target;
    if (e.retries > 0 || e.linear > max / 2 || 2 * e.newton > 3 * target) next *= 0.7;
    else if (e.newton <= target) next *= 1.25;
  } else if (e.linear > max / 2) {
    next *= 0.7;
  } else if (e.linear < std::max(2, max / 8)) {
    next *= 1.25;
  }
  return std::clamp(next, spec.dt_min, spec.dt_max);
}

StepStats TimeLoop::step(Timers& timers, const std::function<void(int, double)>& on_iteration) {
  StepStats st;
  st.step = c_.step + 1;
  const double dt_start = c_.dt, first_step = cg_.first_step();
  const int64_t builds_before = newton_.multigrid_builds();
  save_unknowns();
  // The ring's step-start forces, which its anchors read, from their owners:
  // settled_cost computes the ring's forces itself, so after a migration a
  // new ghost's would otherwise be stale.
  halo_.exchange(c_.z.data(), Halo::kForces, c_.layout, c_.slots());
  exchange_history(c_.x1.data());                     // the ring's bend axes read the ghosts' x1
  ev_.interpolate_hanging(c_.x1.data(), c_.slots());  // ... and hanging ones whose ends were ghosts
  freeze_bend_axes();
  ev_.hysteresis_anchors(c_.x1.data(), c_.z.data(), c_.slots());
  CgSettings cs;
  cs.max_iterations = spec_.max_iterations;
  cs.tolerance = spec_.tolerance;
  cs.numeric = spec_.gradient == GradientMode::Numeric;
  cs.free_particles = free_;
  cs.slope_search = spec_.slope_line_search;
  cs.active_set = spec_.band_active_set;
  cs.adaptive_forcing = spec_.adaptive_forcing;
  // A one-pointer capture: no allocation, whatever stop_requested holds.
  cs.stop_requested = [this] { return stop_requested && stop_requested(); };
  CgResult r;
  for (;;) {
    m_.dt = c_.dt;
    m_.dt_prev = c_.dt_prev;
    predict(1.0);  // the contact's limit on dt is judged on the fall
    if (c_.dt > spec_.dt_min && margin_overshoot() > 0.25 * m_.contact.thickness) {
      c_.dt = std::max(spec_.dt_min, 0.5 * c_.dt);
      ++st.contact_halvings;
      continue;  // a shorter step: no CG spent on this one
    }
    stop_all_at_margin();
    const bool newton = spec_.method == SolverMethod::Newton && !cs.numeric;
    cs.settled_at_start = nullptr;
    if (newton) choose_prediction(timers, st, &cs.settled_at_start);
    r = newton ? newton_.minimize(ev_, c_.z.data(), cs, timers, on_iteration)
               : cg_.minimize(ev_, c_.z.data(), cs, timers, on_iteration);
    st.iterations += r.iterations;
    st.evaluations += r.evaluations;
    st.newton_iterations += r.newton_iterations;
    st.cost = r.cost;
    check_finite(st);
    if (r.converged || r.stopped || c_.dt <= spec_.dt_min * (1 + 1e-12) || st.retries >= 8) break;
    // Not converged: the step was too long for the stiff cost. Retry shorter.
    restore_unknowns();
    c_.dt = std::max(spec_.dt_min, 0.5 * c_.dt);
    ++st.retries;
  }
  if (r.stopped) {  // back to the end of the previous step: a clean state to save
    restore_unknowns();
    c_.dt = dt_start;
    cg_.set_first_step(first_step);
    st.stopped = true;
    st.step = c_.step;
    return st;
  }
  st.converged = r.converged;
  st.multigrid_builds = int(newton_.multigrid_builds() - builds_before);
  st.cost_per_particle = r.cost_per_particle;
  st.dt = c_.dt;
  accept(st);
  c_.time += c_.dt;
  c_.step = st.step;
  st.time = c_.time;
  c_.dt_prev = c_.dt;
  StepEffort e;
  e.linear = r.iterations;
  e.newton = r.newton_iterations;
  e.retries = st.retries;
  c_.dt = next_time_step(spec_, c_.dt, e);
  return st;
}

}  // namespace drape
