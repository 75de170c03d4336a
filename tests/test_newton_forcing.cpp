// Inexact Newton's forcing term (NewtonSolver::forcing, solver.adaptive_forcing):
// the default follows the residual's size; the adaptive one follows how much
// the last Newton iteration reduced it, is held from falling fast while it is
// large, and never asks more than reaching the tolerance needs. On a drape
// through the bands' kinks the adaptive one spends fewer linear iterations
// with every step converged, and keeps results bitwise for any thread count.
#include <gtest/gtest.h>

#include <cmath>

#include "solver/newton.hpp"
#include "support/kink_drape.hpp"

namespace drape::test {
namespace {

CgSettings settings(bool adaptive) {
  CgSettings s;
  s.tolerance = 1e-6;
  s.adaptive_forcing = adaptive;
  return s;
}

TEST(NewtonForcing, DefaultIsTheResidualsRootMeanSquareWithinItsBounds) {
  const CgSettings s = settings(false);
  EXPECT_DOUBLE_EQ(NewtonSolver::forcing(s, 1e-4, 2e-4, 0.5), 1e-2);  // the history is not read
  EXPECT_DOUBLE_EQ(NewtonSolver::forcing(s, 1.0, -1, 0), 0.1);
  EXPECT_DOUBLE_EQ(NewtonSolver::forcing(s, 1e-9, -1, 0), 1e-3);
}

TEST(NewtonForcing, AdaptiveFollowsTheLastReduction) {
  const CgSettings s = settings(true);
  // A step's first iteration: the residual's size, within [1e-3, 0.9].
  EXPECT_DOUBLE_EQ(NewtonSolver::forcing(s, 1e-2, -1, 0), 0.1);
  EXPECT_DOUBLE_EQ(NewtonSolver::forcing(s, 4.0, -1, 0), 0.9);
  // The cost fell 100 times (the residual 10): 0.9 / 100.
  EXPECT_NEAR(NewtonSolver::forcing(s, 1e-2, 1.0, 0.01), 0.009, 1e-15);
  // It fell by half, a kink-bound iteration: a loose solve, 0.45.
  EXPECT_NEAR(NewtonSolver::forcing(s, 0.5, 1.0, 0.01), 0.45, 1e-15);
  // It rose (the slope search descends the energy, not the cost): at most 0.9.
  EXPECT_DOUBLE_EQ(NewtonSolver::forcing(s, 2.0, 1.0, 0.01), 0.9);
}

TEST(NewtonForcing, AdaptiveFallsNoFasterThanTheSquareOfTheLastWhileLarge) {
  const CgSettings s = settings(true);
  // A 1e4-fold fall after a forcing of 0.5: 0.9 * 0.25, not 0.9e-4.
  EXPECT_NEAR(NewtonSolver::forcing(s, 1e-4, 1.0, 0.5), 0.225, 1e-15);
  // A 100-fold fall: after 0.4 (0.9 * 0.16 > 0.1) held at 0.144; after 0.3
  // (0.9 * 0.09 < 0.1) followed, 0.009.
  EXPECT_NEAR(NewtonSolver::forcing(s, 1e-2, 1.0, 0.4), 0.144, 1e-15);
  EXPECT_NEAR(NewtonSolver::forcing(s, 1e-2, 1.0, 0.3), 0.009, 1e-15);
}

TEST(NewtonForcing, AdaptiveAsksNoMoreThanTheToleranceNeeds) {
  const CgSettings s = settings(true);
  // The cost 4 times the tolerance: the residual need fall 2 times; half of
  // that reduction, 0.25, though the last iteration fell 1e4-fold.
  EXPECT_NEAR(NewtonSolver::forcing(s, 4e-6, 4e-2, 0.01), 0.25, 1e-15);
}

using Outcome = KinkDrapeOutcome;

Outcome drape(bool adaptive, int threads, int steps) {
  Scene s = kink_drape_scene(true);
  s.solver.slope_line_search = true;
  s.solver.adaptive_forcing = adaptive;
  return run_kink_drape(s, threads, steps);
}

TEST(NewtonForcing, AdaptiveSameBitsForOneAndTwoThreads) {
  expect_one_and_two_threads_agree([](int threads) { return drape(true, threads, 12); });
}

TEST(NewtonForcing, AdaptiveSpendsFewerLinearIterationsAtAFixedStep) {
  // One fixed dt: both cover the same simulated time, every step converged.
  const Outcome adaptive = drape(true, 1, 30), fixed = drape(false, 1, 30);
  EXPECT_NE(adaptive.checksum, fixed.checksum) << "the forcing should change the path";
  EXPECT_EQ(adaptive.unconverged, 0);
  EXPECT_EQ(fixed.unconverged, 0);
  EXPECT_LT(adaptive.linear, 0.8 * fixed.linear);
}

}  // namespace
}  // namespace drape::test
