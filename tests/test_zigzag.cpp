// Kinks at the mesh spacing (solver/zigzag.hpp): a mesh line that turns back
// and forth from particle to particle is counted, a smooth curve however
// sharp is not, and AMRC's coarse leaves are judged at their own spacing.
#include <gtest/gtest.h>

#include <cmath>

#include "mesh/quadtree.hpp"
#include "solver/zigzag.hpp"
#include "support/scenes.hpp"

namespace drape {
namespace {

using test::flat_scene;
using test::test_fabric;

// Lifts particle (i, j) by f(i, j) (m).
template <class F>
void shape(Simulation& w, F&& f) {
  for (int i = 0; i < w.cloth.grid.ni; ++i)
    for (int j = 0; j < w.cloth.grid.nj; ++j) w.cloth.x()[3 * w.cloth.grid.id(i, j) + 2] += f(i, j);
}

TEST(Zigzag, AFlatClothHasNone) {
  Simulation w(flat_scene(9, 9, 0.08, 0.08), test_fabric());
  const Zigzag z = count_zigzags(w.cloth, w.lists.particles.items, w.red());
  EXPECT_GT(z.pairs, 0);
  EXPECT_EQ(z.zigzags, 0);
}

TEST(Zigzag, ALineThatTurnsBackAndForthAtEveryParticleIsCounted) {
  Simulation w(flat_scene(9, 9, 0.08, 0.08), test_fabric());
  // Up, down, up along i: turns of about 4 * 0.002 / 0.01 = 0.8 rad, alternating.
  shape(w, [](int i, int) { return (i % 2 ? 0.002 : 0.0); });
  const Zigzag z = count_zigzags(w.cloth, w.lists.particles.items, w.red());
  // Every pair along i with triples at both ends (interior i) zigzags; the
  // lines along j stay straight.
  int along_i = 0;
  for (int64_t p : w.lists.particles.items) {
    const int64_t q = w.cloth.next_at(0, p);
    along_i += (w.cloth.triple_on[2 * p] && q >= 0 && w.cloth.triple_on[2 * q]) ? 1 : 0;
  }
  EXPECT_GT(along_i, 0);
  EXPECT_EQ(z.zigzags, along_i);
  EXPECT_NEAR(z.share(), double(along_i) / z.pairs, 1e-15);
  // Below the threshold the same pattern is smooth enough.
  EXPECT_EQ(count_zigzags(w.cloth, w.lists.particles.items, w.red(), 2.0).zigzags, 0);
}

TEST(Zigzag, ASharpButSmoothFoldIsNot) {
  Simulation w(flat_scene(17, 9, 0.16, 0.08), test_fabric());
  // A half circle of radius 5 cm (turns of 0.2 rad per particle, all one way).
  const double h = w.cloth.grid.hi, r = 0.05;
  for (int i = 0; i < 17; ++i)
    for (int j = 0; j < 9; ++j) {
      double* x = w.cloth.x() + 3 * w.cloth.grid.id(i, j);
      const double a = i * h / r;
      x[0] = r * std::sin(a);
      x[2] = r * (1 - std::cos(a));
    }
  const Zigzag z = count_zigzags(w.cloth, w.lists.particles.items, w.red());
  EXPECT_GT(z.pairs, 0);
  EXPECT_EQ(z.zigzags, 0);
}

TEST(Zigzag, CoarseLeavesAreJudgedAtTheirSpacing) {
  Scene s = flat_scene(9, 9, 0.08, 0.08);
  Simulation w(s, test_fabric());
  // A tent line with kinks at the even i, straight in between: on the
  // finest mesh every other particle turns (no neighbouring pair
  // alternates); on leaves two intervals wide every active particle turns,
  // back and forth.
  shape(w, [](int i, int) { return 0.002 * (i % 4 == 0 ? 0 : i % 4 == 2 ? 2 : 1); });
  const Zigzag fine = count_zigzags(w.cloth, w.lists.particles.items, w.red());
  EXPECT_EQ(fine.zigzags, 0);
  Quadtree t(9, 9, 1);
  t.set_levels(std::vector<uint8_t>(size_t(8) * 8, 1));
  w.set_tree(t);
  w.rebuild();
  const Zigzag coarse = count_zigzags(w.cloth, w.lists.particles.items, w.red());
  EXPECT_GT(coarse.zigzags, 0);
  EXPECT_LT(coarse.pairs, fine.pairs);
}

}  // namespace
}  // namespace drape
