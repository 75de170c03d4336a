// The time-step rule (next_time_step): which count chooses dt, by solver.
#include <gtest/gtest.h>

#include "solver/time_loop.hpp"

namespace drape {
namespace {

SolverSpec spec_with(Preconditioner pc) {
  SolverSpec s;
  s.dt_min = 1e-5;
  s.dt_max = 0.05;
  s.max_iterations = 200;
  s.newton_target = 16;
  s.preconditioner = pc;
  return s;
}

StepEffort effort(int linear, int newton, int retries = 0) {
  StepEffort e;
  e.linear = linear;
  e.newton = newton;
  e.retries = retries;
  return e;
}

// Jacobi's linear count grows with dt: it is kept within [max/8, max/2].
TEST(TimeLoopStep, JacobiKeepsTheLinearIterationsInTheirBand) {
  const SolverSpec s = spec_with(Preconditioner::Jacobi);
  EXPECT_DOUBLE_EQ(next_time_step(s, 1e-3, effort(101, 3)), 0.7e-3);
  EXPECT_DOUBLE_EQ(next_time_step(s, 1e-3, effort(24, 3)), 1.25e-3);
  EXPECT_DOUBLE_EQ(next_time_step(s, 1e-3, effort(60, 3)), 1e-3);
  // The Newton count does not enter: many Newton iterations, few linear ones.
  EXPECT_DOUBLE_EQ(next_time_step(s, 1e-3, effort(20, 40)), 1.25e-3);
}

// The multigrid's linear count hardly moves with dt: the Newton count decides.
TEST(TimeLoopStep, MultigridFollowsTheNewtonIterations) {
  const SolverSpec s = spec_with(Preconditioner::Multigrid);
  EXPECT_DOUBLE_EQ(next_time_step(s, 1e-3, effort(60, 16)), 1.25e-3);  // Jacobi's rule would keep dt
  EXPECT_DOUBLE_EQ(next_time_step(s, 1e-3, effort(60, 20)), 1e-3);     // between target and 1.5 target
  EXPECT_DOUBLE_EQ(next_time_step(s, 1e-3, effort(60, 25)), 0.7e-3);
  EXPECT_DOUBLE_EQ(next_time_step(s, 1e-3, effort(60, 24)), 1e-3);     // 1.5 target itself keeps dt
  EXPECT_DOUBLE_EQ(next_time_step(s, 1e-3, effort(10, 2)), 1.25e-3);
}

TEST(TimeLoopStep, MultigridShrinksAfterARetryOrTooManyLinearIterations) {
  const SolverSpec s = spec_with(Preconditioner::Multigrid);
  EXPECT_DOUBLE_EQ(next_time_step(s, 1e-3, effort(30, 4, 1)), 0.7e-3);
  EXPECT_DOUBLE_EQ(next_time_step(s, 1e-3, effort(101, 4)), 0.7e-3);
}

// Nonlinear CG has no preconditioner to speak of: its iterations choose dt.
TEST(TimeLoopStep, NonlinearCgUsesTheIterationBandWhateverThePreconditioner) {
  SolverSpec s = spec_with(Preconditioner::Multigrid);
  s.method = SolverMethod::Cg;
  EXPECT_DOUBLE_EQ(next_time_step(s, 1e-3, effort(60, 0)), 1e-3);
}

TEST(TimeLoopStep, StaysWithinItsBounds) {
  const SolverSpec s = spec_with(Preconditioner::Multigrid);
  EXPECT_DOUBLE_EQ(next_time_step(s, 0.045, effort(10, 2)), 0.05);
  EXPECT_DOUBLE_EQ(next_time_step(s, 1.2e-5, effort(10, 40)), 1e-5);
}

}  // namespace
}  // namespace drape
