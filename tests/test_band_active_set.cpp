// Newton through the bands' kinks (solver/band_active_set.hpp): an element
// that crosses from inside its band to the band's edge within a step gets
// the secant of its stop force, the two branches' slopes weighted by the
// strain spent on each; on a drape the re-solved steps take fewer Newton
// iterations than the tangent's, and the results are bitwise the same for
// any thread count.
#include <gtest/gtest.h>
#include <omp.h>

#include <string>
#include <vector>

#include "solver/band_active_set.hpp"
#include "solver/checksum.hpp"
#include "support/kink_drape.hpp"
#include "support/scenes.hpp"

namespace drape::test {
namespace {

// A bending band f = B q +- H with reversal 5: from the lower edge at q = 0
// the force climbs at 5 B and meets the upper edge at q* = H / (2 B).
struct LinearKink {
  double B = 2.0, H = 0.5;
  Band band = [this] {
    Band b = Band::linear(B, H);
    b.set_reversal(5);
    return b;
  }();
  double anchor() const { return band.anchor(-H, 0.0); }
  double kink() const { return H / (2 * B); }
};

void note_at(BandActiveSet& a, const Band& b, double anchor, int64_t pos, double q) {
  a.note(1, pos, q, b.at(q), b.stop(anchor, q));
}

TEST(BandActiveSet, SecantWeighsTheBranchesByTheStrainSpentOnEach) {
  LinearKink k;
  BandActiveSet a;
  a.enable(true);
  a.fit(1, 2, 2, true);
  a.next_iteration();
  a.at_z();
  note_at(a, k.band, k.anchor(), 0, 0.0);
  note_at(a, k.band, k.anchor(), 1, 0.25 * k.kink());
  a.at_trial();
  note_at(a, k.band, k.anchor(), 0, 2 * k.kink());  // half inside (5 B), half on the edge (B)
  note_at(a, k.band, k.anchor(), 1, 0.75 * k.kink());  // inside all the way
  double s = 0;
  ASSERT_TRUE(a.secant(1, 0, &s));
  EXPECT_NEAR(s, 3 * k.B, 1e-12);
  EXPECT_FALSE(a.secant(1, 1, &s)) << "same branch: its tangent stays";
}

TEST(BandActiveSet, AnElementOnceChangedKeepsItsSecantForTheIteration) {
  LinearKink k;
  BandActiveSet a;
  a.enable(true);
  a.fit(1, 1, 1, true);
  a.next_iteration();
  a.at_z();
  note_at(a, k.band, k.anchor(), 0, 0.25 * k.kink());  // inside
  a.at_trial();
  note_at(a, k.band, k.anchor(), 0, 4 * k.kink());
  double s = 0;
  ASSERT_TRUE(a.secant(1, 0, &s));
  EXPECT_NEAR(s, 1.8 * k.B, 1e-12);  // a fifth of the strain at 5 B, the rest at B
  // The re-solved step falls short of the kink: back inside, the secant is
  // the inside slope (not the tangent swapped back and forth).
  a.at_trial();
  note_at(a, k.band, k.anchor(), 0, 0.5 * k.kink());
  ASSERT_TRUE(a.secant(1, 0, &s));
  EXPECT_NEAR(s, 5 * k.B, 1e-12);
  // A new Newton iteration from the same z, its trial inside: the tangent.
  a.next_iteration();
  a.at_trial();
  note_at(a, k.band, k.anchor(), 0, 0.5 * k.kink());
  EXPECT_FALSE(a.secant(1, 0, &s)) << "a new Newton iteration starts from the tangents";
}

using Outcome = KinkDrapeOutcome;

// The kink drape with or without the active set, `steps` steps; with
// `fixed`, of dt = 4 ms each (the re-solves' linear iterations would
// otherwise shorten dt, and a shorter step needs fewer Newton iterations for
// any tangent).
Outcome drape(bool active_set, int threads, int steps, bool fixed = false) {
  Scene s = kink_drape_scene(fixed);
  s.solver.band_active_set = active_set;
  if (fixed) s.solver.max_iterations = 1000;  // room for the re-solves' linear iterations
  return run_kink_drape(s, threads, steps);
}

TEST(NewtonKinks, ActiveSetSameBitsForOneAndTwoThreads) {
  expect_one_and_two_threads_agree([](int threads) { return drape(true, threads, 12); });
}

// At the same steps, the secants' re-solves save Newton iterations (295
// against 368 here; re-solving with the tangents alone, 360).
TEST(NewtonKinks, ActiveSetTakesFewerNewtonIterations) {
  const Outcome kinks = drape(true, 1, 30, true), tangent = drape(false, 1, 30, true);
  EXPECT_NE(kinks.checksum, tangent.checksum) << "the re-solves should change the path";
  EXPECT_EQ(kinks.unconverged, 0);
  EXPECT_EQ(tangent.unconverged, 0);
  EXPECT_LT(10 * kinks.newton, 9 * tangent.newton) << kinks.newton << " against " << tangent.newton;
}

}  // namespace
}  // namespace drape::test
