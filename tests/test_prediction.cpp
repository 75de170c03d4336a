// A Newton step's first guess (solver.prediction): the last step's motion
// carried on with gravity's free fall added, without it, or whichever of the
// two costs less.
#include <gtest/gtest.h>

#include "support/kink_drape.hpp"

namespace drape::test {
namespace {

using Outcome = KinkDrapeOutcome;

// A 9 x 9 cloth falling freely (no obstacle, no floor): the fall's guess is
// the step's solution, so Newton has nothing to do.
Outcome free_fall(Prediction p, int steps) {
  Scene s = flat_scene(9, 9, 0.2, 0.2);
  s.solver.dt = 2e-3;
  s.solver.prediction = p;
  s.solver.preconditioner = Preconditioner::Multigrid;
  return run_kink_drape(s, 1, steps);
}

// The small drape onto a box, at a fixed 4 ms step.
Scene box_drape_scene(Prediction p) {
  Scene s = kink_drape_scene(true);
  s.solver.slope_line_search = true;
  s.solver.prediction = p;
  return s;
}

Outcome box_drape(Prediction p, int threads, int steps) { return run_kink_drape(box_drape_scene(p), threads, steps); }

TEST(Prediction, CheaperTakesTheFallInAFreeFall) {
  const Outcome fall = free_fall(Prediction::Fall, 10), cheaper = free_fall(Prediction::Cheaper, 10),
                rest = free_fall(Prediction::Rest, 10);
  EXPECT_EQ(cheaper.checksum, fall.checksum);
  EXPECT_EQ(cheaper.newton, fall.newton);
  EXPECT_EQ(fall.unconverged, 0);
  // Without gravity's fall each step starts a weight a particle off.
  EXPECT_GT(rest.newton, fall.newton + 5);
  EXPECT_NE(rest.checksum, fall.checksum);
}

// The Newton iterations of the box drape's steps 121 to 160 (t = 0.48 to
// 0.64 s: landed, the sides settling), at the fixed step.
int settling_newton_iterations(Prediction p) {
  int newton = 0;
  run_kink_drape(box_drape_scene(p), 1, 160, [&newton](int k, const StepStats& st) {
    if (k <= 120) return;
    EXPECT_TRUE(st.converged) << "step " << k;
    newton += st.newton_iterations;
  });
  return newton;
}

// On the box the fall's guess presses g dt^2 into the contact layer and the
// edges holding the hanging sides: some 13 Newton iterations a 4 ms step
// while the cloth settles. The guess without it is nearer there (about 2),
// and the cheaper guess takes it.
TEST(Prediction, CheaperSavesNewtonIterationsOnceTheClothHasLanded) {
  const int fall = settling_newton_iterations(Prediction::Fall),
            cheaper = settling_newton_iterations(Prediction::Cheaper);
  EXPECT_LT(cheaper, fall / 3);
}

TEST(Prediction, CheaperSameBitsForOneAndTwoThreads) {
  expect_one_and_two_threads_agree([](int threads) { return box_drape(Prediction::Cheaper, threads, 30); });
}

}  // namespace
}  // namespace drape::test
