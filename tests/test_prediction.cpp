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

// The cheaper guess evaluates the fall's guess, then the rest's: where it
// takes the rest's, that evaluation is Newton's first, not repeated. A run
// told each step to take the guess the cheaper run took (after the same 120
// steps) has the same state bit for bit, and the cheaper run one evaluation
// more a step where it took the rest's, two where it took the fall's.
TEST(Prediction, CheaperStartsNewtonFromTheRestGuessEvaluation) {
  omp_set_num_threads(1);
  Simulation cheaper(box_drape_scene(Prediction::Cheaper), test_fabric()),
      told(box_drape_scene(Prediction::Cheaper), test_fabric());
  for (Simulation* w : {&cheaper, &told}) w->advance(120);
  int rest_steps = 0;
  for (int k = 0; k < 20; ++k) {
    const StepStats a = cheaper.step();
    SolverSpec guess = told.scene.solver;
    guess.prediction = a.rest_guess ? Prediction::Rest : Prediction::Fall;
    told.loop->set_solver(guess);
    const StepStats b = told.step();
    ASSERT_EQ(a.newton_iterations, b.newton_iterations) << "step " << k;
    EXPECT_EQ(a.evaluations - b.evaluations, a.rest_guess ? 1 : 2) << "step " << k;
    rest_steps += a.rest_guess;
  }
  EXPECT_GT(rest_steps, 10);
  std::vector<int> all;
  for (int t = 0; t < cheaper.tiling.count(); ++t) all.push_back(t);
  EXPECT_EQ(state_checksum(cheaper.cloth, cheaper.tiling, all, cheaper.red()).hex(),
            state_checksum(told.cloth, told.tiling, all, told.red()).hex());
}

TEST(Prediction, CheaperSameBitsForOneAndTwoThreads) {
  expect_one_and_two_threads_agree([](int threads) { return box_drape(Prediction::Cheaper, threads, 30); });
}

}  // namespace
}  // namespace drape::test
