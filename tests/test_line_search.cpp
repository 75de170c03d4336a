// Newton's line search on the step's energy slope (solver/slope_search.hpp):
// on a slope with a band's kink it finds the crossing in a few trials where
// halving stops at a point still far from it; on a cloth it keeps results
// bitwise the same for any thread count.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "solver/checksum.hpp"
#include "solver/slope_search.hpp"
#include "support/kink_drape.hpp"
#include "support/scenes.hpp"

namespace drape::test {
namespace {

// A step's energy along its direction when an element reverses into a band
// at a = kink: the slope g starts at -1, then rises `stiffer` times as fast
// (a reversal of 5 and the edge's slope against the band's inside).
struct KinkedLine {
  double kink = 0.1, stiffer = 20;
  double slope(double a) const { return a < kink ? -1 + a : -1 + kink + stiffer * (a - kink); }
  double energy(double a) const {
    if (a < kink) return -a + 0.5 * a * a;
    const double e = -kink + 0.5 * kink * kink, t = a - kink;
    return e + (-1 + kink) * t + 0.5 * stiffer * t * t;
  }
};

// Runs the search from a = 1 as NewtonSolver does; the accepted a (0: none)
// and the trials it took.
double search(const std::function<double(double)>& g, int* trials) {
  SlopeSearch s(g(0));
  double a = 1;
  for (*trials = 1; *trials <= SlopeSearch::kTrials; ++*trials) {
    const double ga = g(a);
    if (s.accepts(ga)) return a;
    a = s.next(a, ga);
    if (a == 0) return 0;
  }
  return 0;
}

TEST(SlopeSearch, FindsTheCrossingOfAKinkedSlopeInFourTrials) {
  const KinkedLine line;
  int trials = 0;
  const double a = search([&](double t) { return line.slope(t); }, &trials);
  ASSERT_GT(a, 0);
  EXPECT_LE(trials, 4);
  EXPECT_LE(std::fabs(line.slope(a)), 0.01) << "regula falsi lands on a piecewise-linear slope's root";
  // Halving from 1 until the energy decreases (the cost's backtracking on
  // this line) takes three trials, and stops where the slope is still twice
  // as steep as at the start, the other way: a twentieth of the decrease.
  double h = 1;
  int halvings = 1;
  while (!(line.energy(h) < 0)) h *= 0.5, ++halvings;
  EXPECT_EQ(halvings, 3);
  EXPECT_GT(std::fabs(line.slope(h)), 2.0);
  EXPECT_LT(line.energy(a), 20 * line.energy(h));
}

TEST(SlopeSearch, LengthensAStepThatFallsShort) {
  int trials = 0;
  // A tangent three times too stiff: the crossing is at a = 3.
  const double a = search([](double t) { return -1 + t / 3; }, &trials);
  EXPECT_NEAR(a, 3.0, 1e-12);
  EXPECT_EQ(trials, 4);  // 1, 2, 4, then the chord's root
}

TEST(SlopeSearch, GivesUpAtTheLongestStepAndOnAnAscent) {
  int trials = 0;
  EXPECT_EQ(search([](double t) { return -1 + t / 100; }, &trials), 0.0);
  EXPECT_EQ(trials, 3);  // 1, 2, 4: still descending
  EXPECT_FALSE(SlopeSearch(0.5).usable());
  EXPECT_FALSE(SlopeSearch(NAN).usable());
}

TEST(SlopeSearch, CutsBackFromAnOverflow) {
  int trials = 0;
  const double a = search([](double t) { return t > 0.5 ? NAN : -1 + 4 * t; }, &trials);
  EXPECT_NEAR(a, 0.25, 0.125);
  EXPECT_LE(trials, 4);
}

using Outcome = KinkDrapeOutcome;

// The kink drape with or without the slope search, `steps` steps.
Outcome drape(bool slope, int threads, int steps, bool fixed_dt = false) {
  Scene s = kink_drape_scene(fixed_dt);
  s.solver.slope_line_search = slope;
  return run_kink_drape(s, threads, steps);
}

TEST(NewtonLineSearch, SlopeSearchSameBitsForOneAndTwoThreads) {
  expect_one_and_two_threads_agree([](int threads) { return drape(true, threads, 12); });
}

TEST(NewtonLineSearch, SlopeSearchSpendsFewerEvaluationsThanBacktracking) {
  // At one fixed dt both searches cover the same simulated time, so their
  // counts compare the searches alone, not the step sizes they led to.
  const Outcome slope = drape(true, 1, 30, true), halving = drape(false, 1, 30, true);
  EXPECT_NE(slope.checksum, halving.checksum) << "the line search should change the path";
  EXPECT_EQ(slope.unconverged, 0);
  EXPECT_LT(slope.evaluations, halving.evaluations);
  EXPECT_LE(slope.newton, halving.newton);
}

}  // namespace
}  // namespace drape::test
