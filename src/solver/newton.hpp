#pragma once
// Newton's method on the force balance, with the element forces held at their
// hysteresis targets (Band::stop): the same equations and the same zero-cost
// solution as the paper's CG on the total cost, but each Newton step solves
// K d = -r by preconditioned linear CG, whose convergence depends on the
// condition number of K, not its square as for CG on a least-squares cost
// (docs/design.md §6). The line search: backtracking on the cost, each
// accepted step a decrease, or (CgSettings::slope_search) regula falsi on the
// step's energy slope along the direction (solver/slope_search.hpp); before
// either, optionally, a re-solve with the tangent of the band branches the
// full step lands on (solver/band_active_set.hpp).
#include <functional>
#include <vector>

#include "solver/cg.hpp"
#include "solver/memory_table.hpp"
#include "solver/multigrid/divided_level.hpp"
#include "solver/multigrid/multigrid.hpp"
#include "solver/multigrid/rank_rows.hpp"
#include "solver/scene.hpp"

namespace drape {

class NewtonSolver {
 public:
  NewtonSolver(const Cloth& cloth, Minimizer& dots, Preconditioner pc = Preconditioner::Jacobi);

  // Same contract as Minimizer::minimize; `iterations` counts inner CG
  // iterations (each one stiffness product, about one gradient's work).
  CgResult minimize(Evaluator& ev, double* z, const CgSettings& s, Timers& timers,
                    const std::function<void(int, double)>& on_iteration = {});

  // Several ranks' V-cycle: bytes gathered into each rank per cycle and per
  // (the last) build, and over this process's builds and cycles so far (0 on one rank).
  int64_t multigrid_cycle_bytes() const {
    if (dots_.reducer().ranks() == 1) return 0;
    return divided() ? div_.gathered_bytes() : ranks_.vector_bytes();
  }
  // The divided finest level's exchanges: bytes received so far, and its ghosts.
  int64_t multigrid_exchanged_bytes() const { return div_.exchanged_bytes(); }
  int64_t multigrid_ghosts() const { return div_.ghosts(); }
  // Several ranks: the finest level divided (the default) or the whole cycle
  // gathered (the reference); before the first solve.
  void set_divided(bool on) { divided_on_ = on; }
  // This process's CPU seconds in the V-cycles so far (all its threads).
  double precondition_cpu_seconds() const { return pc_cpu_; }
  // ... and in the multigrid's builds (K's assembly included).
  double build_cpu_seconds() const { return build_cpu_; }
  int64_t multigrid_build_bytes() const { return dots_.reducer().ranks() > 1 ? build_bytes_ : 0; }
  int64_t multigrid_builds_bytes() const { return mg_builds_bytes_; }
  int64_t multigrid_cycles_bytes() const { return mg_cycles_bytes_; }
  // The multigrid's levels (empty with Jacobi).
  const std::vector<MultigridLevelStats>& multigrid_stats() const { return mg_.stats(); }
  Preconditioner preconditioner() const { return pc_; }
  // Between steps (grid sequencing's next mesh): the multigrid is built at
  // the next solve.
  void set_preconditioner(Preconditioner pc) {
    pc_ = pc;
    mg_solves_ = 0;
  }
  // Hierarchies built so far (a step's count: the difference across it).
  int64_t multigrid_builds() const { return mg_builds_; }
  // The V-cycle's settings (before the first solve, or between steps).
  int multigrid_levels() const { return pc_ == Preconditioner::Multigrid ? mg_.levels() : 0; }
  void set_multigrid(const MultigridSettings& s) {
    mg_.set_settings(s);
    mg_solves_ = 0;
  }
  // Linear CG for K d = -rho at z, to |r| <= rel_tol |b| or `budget`
  // iterations; the count. d in step() afterwards (compact order).
  int linear_solve(Evaluator& ev, const double* z, int budget, double rel_tol, Timers& tm);
  const std::vector<double>& step() const { return d_; }
  // The linear solve's relative tolerance at a Newton iteration whose cost
  // per particle is c (c_prev the last iteration's, < 0 at a step's first;
  // eta_prev that one's tolerance).
  static double forcing(const CgSettings& st, double c, double c_prev, double eta_prev);
  // Its vectors' capacities (the multigrid's levels not counted).
  void memory(MemoryTable& t) const;
  // Gives its vectors back (a later solve sizes them again).
  void release();
  // After a mesh change, between steps: the compact vectors follow the
  // evaluator's row capacity, if they are held (else the first solve sizes them).
  void fit_vectors(Evaluator& ev) {
    if (!r_.empty()) size_vectors(ev);
  }

 private:
  void setup_multigrid(Evaluator& ev);
  double slope(const Evaluator& ev);
  template <class Trial>
  bool slope_search(Evaluator& ev, double g0, Trial&& trial, CgResult& res, double& c0);
  template <class Trial>
  double through_kinks(Evaluator& ev, double* z, double g0, Trial&& trial, double& last_a, CgResult& res,
                       const CgSettings& st, double eta, Timers& tm);
  bool multigrid_stale(const Evaluator& ev) const;
  // s = M^-1 r (compact vectors): on several ranks with the finest level
  // divided where it can be (divided()), else through the gathered levels.
  void precondition(const double* r, double* s);
  void apply_preconditioner(const double* r, double* s);
  bool divided() const;

  const Cloth& c_;
  Minimizer& dots_;
  // Compact (Minimizer::for_each_unknown's c): the step, residual, scaled
  // residual and diagonal; r_ holds the positions before the line search's
  // trials between solves. 3 per row of the evaluator's (its free and
  // hanging particles' capacity: this rank's, on this mesh). The direction
  // p and K p (the diagonal before the first product) in the evaluator's
  // own numbering, whose first rows are the compact ones: 3 per particle of
  // its room (Evaluator::local_capacity).
  std::vector<double> d_, r_, s_, p_, kpc_, dc_;
  void size_vectors(Evaluator& ev);
  void check_numbering(const Evaluator& ev);
  uint64_t numbered_stamp_ = 0;
  Preconditioner pc_;
  BlockMatrix k_;   // K assembled (multigrid's finest level)
  Multigrid mg_;
  std::vector<int64_t> ids_;  // the free particles, in the compact vectors' order
  uint64_t mg_stamp_ = 0;
  // Several ranks: every rank's rows gathered (RankRows), K of them, and
  // the V-cycle's global right-hand side and result.
  RankRows ranks_;
  BlockMatrix kg_;
  std::vector<double> rg_, xg_;
  DividedLevel div_;
  bool divided_on_ = true;
  // Solves on the current build, and the first's and last's iterations.
  int mg_solves_ = 0, mg_first_ = 0, mg_last_ = 0;
  int64_t mg_builds_ = 0;  // hierarchies built so far
  int64_t build_bytes_ = 0;  // gathered into this rank in the last build (several ranks)
  int64_t mg_builds_bytes_ = 0, mg_cycles_bytes_ = 0;  // gathered into this rank so far (several ranks)
  double pc_cpu_ = 0, build_cpu_ = 0;
};

}  // namespace drape
