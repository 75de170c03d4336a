#pragma once
// Newton's method on the force balance, with the element forces held at their
// hysteresis targets (Band::stop): the same equations and the same zero-cost
// solution as the paper's CG on the total cost, but each Newton step solves
// K d = -r by preconditioned linear CG, whose convergence depends on the
// condition number of K, not its square as for CG on a least-squares cost
// (docs/design.md §6). A backtracking line search on the cost keeps every accepted
// step a decrease.
#include <functional>
#include <vector>

#include "solver/cg.hpp"

namespace drape {

class NewtonSolver {
 public:
  NewtonSolver(const Cloth& cloth, Minimizer& dots);

  // Same contract as Minimizer::minimize; `iterations` counts inner CG
  // iterations (each one stiffness product, about one gradient's work).
  CgResult minimize(Evaluator& ev, double* z, const CgSettings& s, Timers& timers,
                    const std::function<void(int, double)>& on_iteration = {});

 private:
  int linear_solve(Evaluator& ev, const double* z, int budget, double rel_tol, Timers& tm);

  const Cloth& c_;
  Minimizer& dots_;
  // Compact (Minimizer::for_each_unknown's c): the step, residual, scaled
  // residual, direction, K p, diagonal and the positions before the trials.
  std::vector<double> d_, r_, s_, p_, kpc_, dc_, zt_;
  // At z's indices: the direction for the product, K p, the diagonal.
  std::vector<double> pg_, kp_, diag_;
};

}  // namespace drape
