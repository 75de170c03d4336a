#pragma once
// The paper's Algorithm 1: for each time step, minimise the total cost by CG
// starting from the step's history, then accept. Adds what a stiff cost needs
// (docs/design.md §6): a step that does not converge is retried with half the time
// step, and the time step adapts to keep the iterations per step bounded.
#include <functional>

#include "solver/cg.hpp"
#include "solver/cost.hpp"
#include "solver/newton.hpp"
#include "solver/scene.hpp"

namespace drape {

struct StepStats {
  int step = 0;
  double time = 0, dt = 0;
  int iterations = 0, evaluations = 0, retries = 0;
  int newton_iterations = 0;  // Newton steps (solver.method = newton); iterations are then linear CG's
  int contact_halvings = 0;   // dt halved before solving: the prediction overshot the contact margin
  int multigrid_builds = 0;   // multigrid hierarchies built in this step
  bool rest_guess = false;    // Newton started from the guess without gravity's fall (solver.prediction)
  bool converged = false;
  CostTerms cost;
  double cost_per_particle = 0;
  double max_speed = 0;   // m/s over free particles
  int64_t projections = 0;  // particles pushed back out of an obstacle
  // stop_requested() interrupted the step: it was rolled back, the cloth is
  // as it was after the previous step (nothing else in this record counts).
  bool stopped = false;
};

// What a step cost, as the time-step rule reads it.
struct StepEffort {
  int linear = 0;    // CG iterations (Newton's linear ones, or nonlinear CG's)
  int newton = 0;    // Newton iterations (0 with nonlinear CG)
  int retries = 0;   // halvings after an unconverged attempt
};

// The next step's dt from this step's (a pure function: a restarted run
// redoes it). See docs/design.md §6.
double next_time_step(const SolverSpec& spec, double dt, const StepEffort& e);

class TimeLoop {
 public:
  TimeLoop(Cloth& cloth, Model& model, const ActiveLists& lists, const Tiling& tiling,
           const LoopPolicy& policy, const Reducer& red, const SolverSpec& spec,
           const Halo& halo = no_halo());

  // Advances one step, or leaves the cloth untouched if stopped (see
  // StepStats::stopped). Throws NumericalError on NaN/Inf or divergence.
  StepStats step(Timers& timers, const std::function<void(int, double)>& on_iteration = {});

  // Polled every iteration (see CgSettings::stop_requested).
  std::function<bool()> stop_requested;

  Evaluator& evaluator() { return ev_; }
  Minimizer& minimizer() { return cg_; }
  NewtonSolver& newton() { return newton_; }
  int64_t free_particles() const { return free_; }
  // Jacobi or the multigrid (never `auto`: Simulation resolves it per mesh,
  // stage_solver), with its dt_max, max_iterations and first guess,
  // switched between steps; dt's rule follows it (next_time_step).
  Preconditioner preconditioner() const { return spec_.preconditioner; }
  void set_solver(const SolverSpec& s) {
    if (s.preconditioner != spec_.preconditioner) newton_.set_preconditioner(s.preconditioner);
    spec_.preconditioner = s.preconditioner;
    spec_.dt_max = s.dt_max;
    spec_.max_iterations = s.max_iterations;
    spec_.prediction = s.prediction;
  }

  // The arrays of the evaluator, both solvers and the step's saved unknowns.
  void memory(MemoryTable& t) const;
  // After the last step: the solvers give their vectors back, so that the
  // output's buffers (the picture's) take memory the run no longer uses
  // instead of adding to its peak. A later step sizes them again.
  void release_solvers() {
    cg_.release();
    newton_.release();
  }

  // After AMRC changed the mesh (and the lists were rebuilt): the
  // evaluator's arrays and the solvers' compact vectors grow here, not in the
  // next step, where the lists outgrew them; with `new_stage` (grid
  // sequencing's next level) they are sized to the new lists, shrinking too
  // (Evaluator::fit_to_lists).
  void mesh_changed(bool new_stage = false) {
    ev_.fit_to_lists(new_stage);
    newton_.fit_vectors(ev_);
    cg_.fit_vectors(new_stage);
    fit_saved(new_stage);
    free_ = red_.sum_i64(lists_.particles.size());
  }

  // The bending axis of every triple from the step-start positions x1.
  void freeze_bend_axes();

  // Ghost and hanging entries of z (and with `history`, of x1 and x2) made
  // current: before AMRC carries values from old corners, before output.
  void refresh_ghosts(bool history);

 private:
  void predict(double fall);
  void choose_prediction(Timers& tm, StepStats& st, const CostTerms** settled);
  void stop_at_margin(int64_t p);
  void stop_all_at_margin();
  double margin_overshoot() const;
  void fit_saved(bool exact);
  void save_unknowns();
  void restore_unknowns();
  void accept(StepStats& st);
  void check_finite(const StepStats& st) const;
  void exchange_history(double* x);
  void map_history_halo();

  Cloth& c_;
  Model& m_;
  const ActiveLists& lists_;
  const Reducer& red_;
  const Halo& halo_;
  SolverSpec spec_;
  Evaluator ev_;
  Minimizer cg_;
  NewtonSolver newton_;
  CostTerms guess_cost_;  // the guess's cost, where choose_prediction settled it last
  std::vector<double> z_saved_;  // this rank's unknowns at the step's start, compact
  // The halo plan's particles as slots of x1, x2 (-1: not held), sent and
  // received, for the plan and the slots of the versions below.
  std::vector<int32_t> hist_send_, hist_recv_;
  uint64_t hist_plan_ = ~uint64_t(0), hist_held_ = ~uint64_t(0);
  int64_t free_ = 0;
};

}  // namespace drape
