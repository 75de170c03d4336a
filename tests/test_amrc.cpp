// The AMRC hierarchy: 2:1 balance and mass after random refine/coarsen
// sequences, hanging particles on their coarse sides, refine-then-coarsen as
// the identity, and the criterion taking a flat cloth to the coarsest mesh
// and a sharp fold to the finest. Grids are clipped (not k * 2^L + 1).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "amrc/amrc.hpp"
#include "amrc/criterion.hpp"
#include "mesh/quadtree.hpp"
#include "amrc/sequence.hpp"
#include "mesh/cloth.hpp"
#include "support/scenes.hpp"

namespace drape::test {
namespace {

constexpr int kNi = 23, kNj = 19, kMaxLevel = 3;
constexpr double kHi = 0.01, kHj = 0.012, kDensity = 0.43;

double total_mass(const Quadtree& t) {
  std::vector<double> m;
  t.masses(kDensity, kHi, kHj, nullptr, m);
  double s = 0;
  for (double v : m) s += v;
  return s;
}

double exact_mass() { return kDensity * (kNi - 1) * kHi * (kNj - 1) * kHj; }

// A random leaf refined, or the parent of one coarsened.
void random_change(Quadtree& t, std::mt19937& rng) {
  const Cell c = t.leaf_at(int(rng() % (kNi - 1)), int(rng() % (kNj - 1)));
  if (rng() % 2) {
    t.refine(c);
  } else {
    const int l = c.level + 1;
    t.coarsen({(c.i >> l) << l, (c.j >> l) << l, l});
  }
}

Quadtree coarsest() {
  Quadtree t(kNi, kNj, kMaxLevel);
  const std::vector<double> flat(size_t(kNi) * kNj, 0.0);
  for (int pass = 0; pass < 10; ++pass) adapt(t, flat, 1.0, 0.5);
  return t;
}

TEST(Quadtree, StartsAtTheFinestMesh) {
  Quadtree t(kNi, kNj, kMaxLevel);
  std::vector<uint8_t> flags, level;
  t.mark(flags, level);
  for (size_t p = 0; p < flags.size(); ++p) {
    EXPECT_EQ(flags[p], kActive) << p;
    EXPECT_EQ(level[p], 0) << p;
  }
  EXPECT_TRUE(t.balanced());
  EXPECT_NEAR(total_mass(t), exact_mass(), 1e-12 * exact_mass());
}

TEST(Quadtree, RandomSequencesKeepBalanceMassAndHangingParticles) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    std::mt19937 rng(seed);
    Quadtree t = seed % 2 ? Quadtree(kNi, kNj, kMaxLevel) : coarsest();
    int hanging_seen = 0;
    for (int step = 0; step < 150; ++step) {
      random_change(t, rng);
      ASSERT_TRUE(t.balanced()) << "seed " << seed << " step " << step;
      ASSERT_NEAR(total_mass(t), exact_mass(), 1e-12 * exact_mass()) << "seed " << seed << " step " << step;
      std::vector<uint8_t> flags, level;
      t.mark(flags, level);
      std::vector<double> mass;
      t.masses(kDensity, kHi, kHj, nullptr, mass);
      for (int64_t p = 0; p < int64_t(flags.size()); ++p) {
        int64_t a = -1, b = -1;
        const bool hangs = t.hanging_parents(p, a, b);
        ASSERT_EQ(hangs, bool(flags[p] & kHanging)) << p;
        if (!(flags[p] & kActive) || hangs) {
          ASSERT_EQ(mass[p], 0.0) << "particle " << p << " carries mass";
        }
        if (!hangs) continue;
        ++hanging_seen;
        // Between two active particles on a grid line; in the middle unless
        // the side is clipped at the far border.
        ASSERT_TRUE(flags[a] & kActive);
        ASSERT_TRUE(flags[b] & kActive);
        ASSERT_TRUE(a < p && p < b) << "hanging particle " << p << " outside " << a << "-" << b;
        ASSERT_TRUE(a / kNj == b / kNj || a % kNj == b % kNj) << "side " << a << "-" << b << " not on a grid line";
        const bool clipped = b / kNj == kNi - 1 || b % kNj == kNj - 1;
        if (!clipped) {
          ASSERT_EQ(2 * p, a + b) << "hanging particle " << p << " not in the middle of " << a << "-" << b;
        }
      }
    }
    EXPECT_GT(hanging_seen, 0) << "seed " << seed << " never made a hanging particle";
  }
}

TEST(Quadtree, HangingParticlesLieOnTheirCoarseSide) {
  std::mt19937 rng(11);
  Quadtree t = coarsest();
  for (int step = 0; step < 60; ++step) random_change(t, rng);
  std::vector<double> x(3 * kNi * kNj);
  std::uniform_real_distribution<double> u(-1, 1);
  for (double& v : x) v = u(rng);
  t.interpolate_hanging(x.data());
  std::vector<uint8_t> flags, level;
  t.mark(flags, level);
  int checked = 0;
  for (int64_t p = 0; p < kNi * kNj; ++p) {
    int64_t a, b;
    if (!t.hanging_parents(p, a, b)) continue;
    // On the straight line between the ends, at its share of the side.
    const double t = double(p - a) / double(b - a);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(x[3 * p + k], (1 - t) * x[3 * a + k] + t * x[3 * b + k], 1e-15) << p;
    ++checked;
  }
  EXPECT_GT(checked, 0);
}

TEST(Quadtree, RefineThenCoarsenIsTheIdentity) {
  std::mt19937 rng(5);
  Quadtree t = coarsest();
  for (int step = 0; step < 40; ++step) random_change(t, rng);
  std::vector<Cell> leaves;
  t.leaves(leaves);
  int tried = 0;
  for (const Cell& c : leaves) {
    if (!t.can_refine(c)) continue;
    const Quadtree before = t;
    std::vector<uint8_t> f0, l0, f1, l1;
    std::vector<double> m0, m1;
    before.mark(f0, l0);
    before.masses(kDensity, kHi, kHj, nullptr, m0);
    t.refine(c);
    t.coarsen(c);
    // A refinement that had to refine neighbours first is undone by
    // coarsening them too.
    for (int pass = 0; pass < kMaxLevel; ++pass) {
      std::vector<Cell> now;
      before.leaves(now);
      for (const Cell& o : now) t.coarsen(o);
    }
    t.mark(f1, l1);
    t.masses(kDensity, kHi, kHj, nullptr, m1);
    ASSERT_EQ(f0, f1) << "leaf " << c.i << "," << c.j << " level " << c.level;
    ASSERT_EQ(l0, l1);
    ASSERT_EQ(m0, m1);
    ++tried;
  }
  EXPECT_GT(tried, 3);
}

TEST(Criterion, FlatClothCoarsensToTheCoarsestLevel) {
  const Quadtree t = coarsest();
  std::vector<Cell> leaves;
  t.leaves(leaves);
  for (const Cell& c : leaves) EXPECT_EQ(c.level, kMaxLevel) << c.i << "," << c.j;
  EXPECT_TRUE(t.balanced());
  EXPECT_NEAR(total_mass(t), exact_mass(), 1e-12 * exact_mass());
}

// amrc.coarsen_speed: a flat cloth whose lower rows still move keeps the
// finest mesh wherever a cell holds a moving particle, and coarsens the rest.
TEST(Criterion, MovingParticlesKeepTheirCellsFine) {
  Quadtree t(kNi, kNj, kMaxLevel);
  const std::vector<double> flat(size_t(kNi) * kNj, 0.0);
  const int moving_rows = 6;  // i < 6 moves at 1 m/s, the rest at 1 mm/s
  std::vector<double> speed(flat.size(), 1e-3);
  for (int i = 0; i < moving_rows; ++i)
    for (int j = 0; j < kNj; ++j) speed[size_t(i) * kNj + j] = 1.0;
  std::vector<Cell> scratch;
  for (int pass = 0; pass < 10; ++pass) adapt(t, flat, Thresholds{1.0, 0.5, 0.1}, scratch, &speed);
  ASSERT_TRUE(t.balanced());
  std::vector<Cell> leaves;
  t.leaves(leaves);
  int coarse = 0;
  for (const Cell& c : leaves) {
    if (c.i < moving_rows) {
      EXPECT_EQ(c.level, 0) << "leaf at " << c.i << "," << c.j << " holds moving particles";
    }
    coarse += c.level == kMaxLevel;
  }
  EXPECT_GT(coarse, 0) << "the still rows should coarsen to the coarsest level";
  EXPECT_NEAR(total_mass(t), exact_mass(), 1e-12 * exact_mass());
  // Once everything is slow, everything coarsens.
  std::fill(speed.begin(), speed.end(), 1e-3);
  for (int pass = 0; pass < 10; ++pass) adapt(t, flat, Thresholds{1.0, 0.5, 0.1}, scratch, &speed);
  t.leaves(leaves);
  for (const Cell& c : leaves) EXPECT_EQ(c.level, kMaxLevel) << c.i << "," << c.j;
}

TEST(Criterion, SharpFoldRefinesToTheFinestLevel) {
  Quadtree t = coarsest();
  // A fold along the grid line i = 9: the cloth turns by 90 degrees there.
  const int fold = 9;
  auto pos = [&](int i, int j) {
    const double s = (i - fold) * kHi;
    return std::array<double, 3>{std::min(s, 0.0), j * kHj, std::max(s, 0.0)};
  };
  std::vector<double> indicator(size_t(kNi) * kNj, 0.0);
  for (int i = 1; i + 1 < kNi; ++i)
    for (int j = 0; j < kNj; ++j) {
      const auto a = pos(i - 1, j), b = pos(i, j), c = pos(i + 1, j);
      double u[3], v[3], uv = 0, uu = 0, vv = 0;
      for (int k = 0; k < 3; ++k) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - b[k];
        uv += u[k] * v[k];
        uu += u[k] * u[k];
        vv += v[k] * v[k];
      }
      indicator[size_t(i) * kNj + j] = std::acos(std::clamp(uv / std::sqrt(uu * vv), -1.0, 1.0));
    }
  for (int pass = 0; pass < 10; ++pass) adapt(t, indicator, 0.5, 0.1);
  ASSERT_TRUE(t.balanced());
  std::vector<Cell> leaves;
  t.leaves(leaves);
  int finest = 0, coarse = 0;
  for (const Cell& c : leaves) {
    const bool touches = c.i <= fold && fold <= t.i_end(c);
    if (touches) {
      EXPECT_EQ(c.level, 0) << "leaf at " << c.i << "," << c.j << " on the fold";
    }
    finest += touches && c.level == 0;
    coarse += !touches && c.level == kMaxLevel;
  }
  EXPECT_GT(finest, 0);
  EXPECT_GT(coarse, 0) << "far from the fold the mesh should stay coarse";
  EXPECT_NEAR(total_mass(t), exact_mass(), 1e-12 * exact_mass());
}

// A pass must not depend on the order it visits cells in: a mirror-symmetric
// mesh and indicator stay mirror-symmetric. Here a band of finest leaves
// (rows 4-11 of 16) lies between coarse parents whose merges wait on the
// band's: merged one by one in row order, the parent before the band stayed
// and the one after merged, and a symmetric drape leaned to one side.
TEST(Criterion, APassIsItsOwnMirrorImage) {
  constexpr int n = 17, cells = n - 1;
  Quadtree t(n, n, 2);
  std::vector<uint8_t> levels(size_t(cells) * cells, 1);
  for (int ci = 4; ci < 12; ++ci)
    for (int cj = 0; cj < cells; ++cj) levels[size_t(ci) * cells + cj] = 0;
  t.set_levels(levels);
  const std::vector<double> flat(size_t(n) * n, 0.0);
  for (int pass = 0; pass < 3; ++pass) {
    adapt(t, flat, 1.0, 0.5);
    ASSERT_TRUE(t.balanced()) << "pass " << pass;
    for (int ci = 0; ci < cells; ++ci)
      for (int cj = 0; cj < cells; ++cj) {
        ASSERT_EQ(t.leaf_at(ci, cj).level, t.leaf_at(cells - 1 - ci, cj).level)
            << "pass " << pass << ": cell row " << ci << " and its mirror row " << cells - 1 - ci << ", column " << cj;
      }
  }
  for (int ci = 0; ci < cells; ++ci) EXPECT_EQ(t.leaf_at(ci, 0).level, 2) << ci << ": a flat cloth ends coarsest";
}

// The inside mask (bit 0: the mesh puts the particle inside an obstacle;
// bit l: merging the level-l cell round it would): a flat cloth coarsens
// everywhere but where a merge would cut in, and a leaf holding a particle
// placed inside splits down to the finest mesh.
// The criterion on its values, as adapt() once read them: each leaf's and
// each parent's largest indicator and speed (from 0) against the
// thresholds. The reference for the bits adapt() reads now.
AdaptStats adapt_by_values(Quadtree& t, const std::vector<double>& ind, const std::vector<double>& speed,
                           const Thresholds& th) {
  auto largest = [&](const Cell& c, const std::vector<double>& f) {
    double m = 0;
    for (int i = c.i; i <= t.i_end(c); ++i)
      for (int j = c.j; j <= t.j_end(c); ++j) m = std::max(m, f[size_t(i) * t.nj() + j]);
    return m;
  };
  auto scale = [&](int level) { return th.by_width ? std::ldexp(1.0, level - t.max_level()) : 1.0; };
  AdaptStats st;
  std::vector<Cell> leaves;
  t.leaves(leaves);
  for (const Cell& c : leaves)
    if (t.leaf_at(c.i, c.j) == c && t.can_refine(c) && largest(c, ind) * scale(c.level) > th.refine) {
      t.refine(c);
      ++st.refined;
    }
  t.leaves(leaves);
  std::vector<Cell> merge;
  for (const Cell& c : leaves) {
    const int l = c.level + 1;
    const Cell parent{(c.i >> l) << l, (c.j >> l) << l, l};
    if (c.level >= t.max_level() || parent.i != c.i || parent.j != c.j) continue;
    if (t.can_coarsen(parent) && largest(parent, ind) * scale(c.level) < th.coarsen &&
        largest(parent, speed) < th.coarsen_speed)
      merge.push_back(parent);
  }
  for (const Cell& c : merge) st.coarsened += t.coarsen(c) ? 1 : 0;
  return st;
}

// Random indicators and speeds, some at the thresholds exactly and scaled
// by the leaf width: adapt() on the bits builds the same trees, pass after
// pass, as the largest values do.
TEST(Criterion, BitsSplitAndMergeAsTheLargestValues) {
  std::mt19937 rng(11);
  for (bool by_width : {false, true}) {
    const Thresholds th{0.4, 0.1, 0.05, by_width};
    Quadtree bits(kNi, kNj, kMaxLevel), values(kNi, kNj, kMaxLevel);
    std::vector<Cell> scratch;
    int changed = 0;
    for (int pass = 0; pass < 12; ++pass) {
      // A band of rows bent (some exactly at refine over a level's scale),
      // elsewhere small values, some exactly at coarsen (scaled alike); a
      // few particles at coarsen_speed.
      std::vector<double> ind(size_t(kNi) * kNj), speed(ind.size());
      const int band = int(rng() % (kNi - 3));
      for (size_t p = 0; p < ind.size(); ++p) {
        const int i = int(p / kNj), k = int(rng() % 4);
        const bool bent = i >= band && i < band + 3;
        ind[p] = bent ? (rng() % 2 ? 0.4 : 0.9) * std::ldexp(1.0, k)
                      : (rng() % 3 ? 0.01 * (rng() % 5) : 0.1 * std::ldexp(1.0, k));
        speed[p] = rng() % 40 == 0 ? 0.05 : 0.01;
      }
      const AdaptStats a = adapt(bits, ind, th, scratch, &speed);
      const AdaptStats b = adapt_by_values(values, ind, speed, th);
      ASSERT_EQ(bits.levels(), values.levels()) << "pass " << pass << (by_width ? ", by width" : "");
      EXPECT_EQ(a.refined, b.refined);
      EXPECT_EQ(a.coarsened, b.coarsened);
      changed += a.refined + a.coarsened;
    }
    EXPECT_GT(changed, 20) << "the passes changed too little to tell";
  }
}

TEST(Criterion, NoLeafCutsIntoTheObstacle) {
  const std::vector<double> flat(size_t(kNi) * kNj, 0.0);
  std::vector<uint32_t> inside(flat.size(), 0);
  const int64_t stays = int64_t(9) * kNj + 5;  // merging level 2 round (9, 5) would cut in
  inside[stays] = 4u;                          // bit 2
  Quadtree t(kNi, kNj, kMaxLevel);
  std::vector<Cell> scratch;
  for (int pass = 0; pass < 10; ++pass) adapt(t, flat, Thresholds{1.0, 0.5}, scratch, nullptr, &inside);
  ASSERT_TRUE(t.balanced());
  for (int ci : {8, 9})
    for (int cj : {4, 5}) EXPECT_EQ(t.leaf_at(ci, cj).level, 1) << ci << "," << cj << ": its level-2 cell cuts in";
  EXPECT_EQ(t.leaf_at(20, 16).level, kMaxLevel) << "far from it the cloth coarsens";
  // Now the coarse leaf round (17, 13) places that particle inside: it splits to the finest.
  const int64_t cut = int64_t(17) * kNj + 13;
  ASSERT_GT(t.leaf_at(17, 13).level, 0);
  std::fill(inside.begin(), inside.end(), 0u);
  inside[cut] = 1u;
  for (int pass = 0; pass < 4; ++pass) adapt(t, flat, Thresholds{1.0, 0.5}, scratch, nullptr, &inside);
  ASSERT_TRUE(t.balanced());
  for (int ci : {16, 17})
    for (int cj : {12, 13}) EXPECT_EQ(t.leaf_at(ci, cj).level, 0) << ci << "," << cj;
}

}  // namespace
}  // namespace drape::test

// ------------------------------------------------------- the solver's view --

namespace drape::test {
namespace {

// Internal forces are action and reaction: summed over every particle that
// has an equation they cancel, hanging particles included, because those
// pass their forces on to the ends of their sides. So the residuals' sum is
// the inertia-and-gravity sum alone.
TEST(AmrcMesh, InternalForcesCancelWithHangingParticles) {
  Scene s = flat_scene(13, 11, 0.12, 0.10);
  Simulation w(s, test_fabric());
  w.set_tree(mixed_tree());
  w.rebuild();
  ASSERT_GE(w.lists.hanging.size(), 4u);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  Cloth& c = w.cloth;
  for (int64_t k = 0; k < 3 * c.grid.n(); ++k) c.z[k] += 0.2 * c.grid.hi * u(rng);
  const Layout& L = c.layout;
  for (int64_t k = L.tension(); k < L.size(); ++k) c.z[k] = 10.0 * u(rng);
  w.model.dt = w.model.dt_prev = 1e-3;
  w.loop->freeze_bend_axes();
  std::vector<double> grad(c.z.size());
  w.loop->evaluator().evaluate(c.z.data(), grad.data());
  // At z's indices: the hanging particles' entries too.
  const std::vector<double>& rho = w.loop->evaluator().gradient_residual();
  double sum[3] = {0, 0, 0}, inertia[3] = {0, 0, 0}, scale = 0;
  for (int64_t p : w.lists.particles.items)
    for (int k = 0; k < 3; ++k) {
      sum[k] += rho[3 * p + k] * w.model.force_scale;
      const double a = w.model.accel_coeff() * (c.z[3 * p + k] - c.x1[3 * p + k] - (c.x1[3 * p + k] - c.x2[3 * p + k]));
      inertia[k] += c.mass_at(p) * (a - w.model.gravity[k]);
      scale = std::max(scale, std::fabs(rho[3 * p + k] * w.model.force_scale));
    }
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(sum[k], inertia[k], 1e-9 * scale) << "component " << k;
  // Without passing them on, the hanging particles' forces would be lost.
  double lost = 0;
  for (const HangingLink& g : w.lists.hanging) lost += std::fabs(rho[3 * g.h]);
  EXPECT_GT(lost, 0.0) << "hanging particles should see their ends' residuals";
}

}  // namespace
}  // namespace drape::test

namespace drape::test {
namespace {

// A flat cloth under uniform tension T (per unit width) in both directions,
// at rest, without gravity: on any mesh the interior particles are in
// balance. Returns the largest internal force (N) on a free particle at least
// `margin` intervals from the border, with its residual unscaled.
double largest_interior_force(Simulation& w, int margin) {
  Cloth& c = w.cloth;
  const double T = 50.0, stretch = 1.01;
  for (int64_t p = 0; p < c.grid.n(); ++p) {
    const double x[3] = {stretch * c.grid.i_of(p) * c.grid.hi, stretch * c.grid.j_of(p) * c.grid.hj, 0.3};
    for (int k = 0; k < 3; ++k) c.z[3 * p + k] = c.x1[3 * p + k] = c.x2[3 * p + k] = x[k];
  }
  const Layout& L = c.layout;
  for (int64_t k = L.tension(); k < L.size(); ++k) c.z[k] = k < L.moment() ? T : 0.0;
  for (double& g : w.model.gravity) g = 0;
  w.model.dt = w.model.dt_prev = 1e-3;
  w.model.use_stretch = w.model.use_bend = w.model.use_shear = false;
  w.loop->freeze_bend_axes();
  w.loop->evaluator().evaluate(c.z.data(), nullptr);
  const std::vector<double>& rho = w.loop->evaluator().residual();  // list order
  const std::vector<int64_t>& ids = w.lists.particles.items;
  double worst = 0;
  for (size_t r = 0; r < ids.size(); ++r) {
    const int i = c.grid.i_of(ids[r]), j = c.grid.j_of(ids[r]);
    if (i < margin || j < margin || i >= c.grid.ni - margin || j >= c.grid.nj - margin) continue;
    for (int k = 0; k < 3; ++k) worst = std::max(worst, std::fabs(rho[3 * r + k]) * w.model.force_scale);
  }
  return worst;
}

// Across a split and a merge the force balance on the particles that
// survive does not jump: on the uniformly tensioned cloth every interior
// particle stays within a quarter of one coarse edge's force (T h_c) of
// balance, hanging-particle interfaces included.
TEST(AmrcMesh, ForceOnSurvivingParticlesStaysBalancedAcrossSplitAndMerge) {
  Scene s = flat_scene(17, 17, 0.16, 0.16);
  Simulation w(s, test_fabric());
  Quadtree t(17, 17, 2);
  const std::vector<double> flat(17 * 17, 0.0);
  for (int pass = 0; pass < 4; ++pass) adapt(t, flat, 1.0, 0.5);
  w.set_tree(t);
  w.rebuild();
  const double coarse_edge = 50.0 * 4 * w.cloth.grid.hi;  // T h_c, N
  const double before = largest_interior_force(w, 4);
  EXPECT_LE(before, 1e-9 * coarse_edge) << "a uniform coarse mesh is in balance";
  t.refine(t.leaf_at(8, 8));  // split (cascading to keep the balance)
  w.set_tree(t);
  w.rebuild();
  ASSERT_FALSE(w.lists.hanging.empty());
  const double split = largest_interior_force(w, 4);
  EXPECT_LE(split, 0.25 * coarse_edge) << "after the split";
  t.coarsen(Cell{8, 8, 2});  // merge back
  w.set_tree(t);
  w.rebuild();
  const double merged = largest_interior_force(w, 4);
  EXPECT_LE(merged, 0.25 * coarse_edge) << "after the merge";
  std::printf("largest interior force / (T h_c): uniform %.3g, split %.3g, merged %.3g\n",
              before / coarse_edge, split / coarse_edge, merged / coarse_edge);
}

// amrc.indicator = "deflection": on a cloth bent round a cylinder, the
// turning angle doubles with the spacing (0.1 rad at the finest, 0.2 and 0.4
// at levels 1 and 2). Compared with thresholds 0.15/0.03 as they stand, every
// leaf splits down to the finest mesh; scaled by the leaf's width, a level-1
// leaf turns 0.2 x 1/2 = 0.1 < 0.15 and stays, and finest children merge
// (0.1 x 1/4 < 0.03): level 1 is reached from either end.
TEST(AmrcMesh, DeflectionStopsAUniformBendOneLevelCoarser) {
  constexpr int n = 17;
  constexpr double h = 0.01, radius = 0.1;
  auto leaf_levels = [&](bool by_width, uint8_t start) {
    Simulation w(flat_scene(n, n, (n - 1) * h, (n - 1) * h), test_fabric());
    Amrc amrc(w.cloth, 2);
    amrc.restore(std::vector<uint8_t>(size_t(n - 1) * (n - 1), start));
    amrc.apply(w.cloth, w.fabric.density, w.scene.cloth.shear);
    auto on_cylinder = [&] {  // every particle, solved or not, on the exact bend
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const double a = (i - (n - 1) / 2) * h / radius;
          const double y[3] = {radius * std::sin(a), j * h, radius * (1 - std::cos(a))};
          for (int k = 0; k < 3; ++k) {
            const int64_t u = 3 * (int64_t(i) * n + j) + k;
            w.cloth.z[u] = w.cloth.x1[u] = w.cloth.x2[u] = y[k];
          }
        }
    };
    for (int pass = 0; pass < 6; ++pass) {
      on_cylinder();
      amrc.adapt(w.cloth, w.fabric.density, w.scene.cloth.shear, Thresholds{0.15, 0.03, 0, by_width});
    }
    std::vector<Cell> leaves;
    amrc.tree().leaves(leaves);
    std::vector<int> levels;
    for (const Cell& c : leaves) levels.push_back(c.level);
    return levels;
  };
  for (uint8_t start : {uint8_t(0), uint8_t(2)}) {
    for (int l : leaf_levels(false, start)) EXPECT_EQ(l, 0) << "angle, from level " << int(start);
    for (int l : leaf_levels(true, start)) EXPECT_EQ(l, 1) << "deflection, from level " << int(start);
  }
}

// A 33 x 9 cloth folded across i onto itself (flat for i <= 14, a half
// turn of radius 1.5 h, back above the lower half 3 pair distances up) on
// level-2 leaves, adapted a few times: with self-contact's pair distance
// the criterion splits the flat leaves far from the fold, where each sheet
// faces the other, down to the finest level (amrc/near.cpp); without it
// they are flat and stay as coarse as they can.
TEST(AmrcMesh, SheetsFacingEachOtherSplitToTheFinestLevel) {
  constexpr int ni = 33, nj = 9;
  constexpr double h = 0.01, r = 1.5 * h, s0 = 14 * h;
  auto fold = [&](Simulation& w) {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j) {
        const double s = i * h;
        double x, z;
        if (s <= s0) {
          x = s, z = 0;
        } else if (s <= s0 + M_PI * r) {
          x = s0 + r * std::sin((s - s0) / r), z = r * (1 - std::cos((s - s0) / r));
        } else {
          x = s0 - (s - s0 - M_PI * r), z = 2 * r;
        }
        const double y[3] = {x, j * h, z};
        for (int k = 0; k < 3; ++k) {
          const int64_t u = 3 * (int64_t(i) * nj + j) + k;
          w.cloth.z[u] = w.cloth.x1[u] = w.cloth.x2[u] = y[k];
        }
      }
  };
  for (bool near : {true, false}) {
    Simulation w(flat_scene(ni, nj, (ni - 1) * h, (nj - 1) * h), test_fabric());
    Amrc amrc(w.cloth, 2, near);
    amrc.restore(std::vector<uint8_t>(size_t(ni - 1) * (nj - 1), 2));
    amrc.apply(w.cloth, w.fabric.density, w.scene.cloth.shear);
    const double pair = 2 * w.model.contact.thickness;
    ASSERT_NEAR(pair, h, 1e-12);
    Thresholds th{0.1, 0.02};
    th.pair_distance = near ? pair : 0.0;
    int refined_near = 0;
    for (int pass = 0; pass < 4; ++pass) {
      fold(w);
      refined_near += amrc.adapt(w.cloth, w.fabric.density, w.scene.cloth.shear, th).refined_near;
    }
    const Quadtree& t = amrc.tree();
    ASSERT_TRUE(t.balanced());
    EXPECT_EQ(refined_near > 0, near);
    for (int ci : {0, 1, 2, 3, 28, 29, 30, 31})
      for (int cj = 0; cj < nj - 1; ++cj)
        EXPECT_EQ(t.leaf_at(ci, cj).level, near ? 0 : 2) << ci << "," << cj << (near ? " near" : "");
  }
}

// The near mask against the plain loop over every pair of active particles
// with the same pair test (near.cpp's reach rule), entry by entry: a 65 x 65
// cloth folded twice into three layers whose gap widens along j, jittered,
// on uniform leaves of each level, so that every level's bits are set at
// some particles and clear at others.
unsigned near_mask_by_pairs(const Cloth& c, const Quadtree& t, double pair, int64_t p) {
  const Grid& g = c.grid;
  if (!c.active(p)) return 0;
  const double diag = std::hypot(g.hi, g.hj), wide = std::max(g.hi, g.hj);
  auto split = [&](int l) { return pair + std::ldexp(1.5 * diag + wide, l); };
  const int ip = g.i_of(p), jp = g.j_of(p);
  int coarsest = 0;
  for (int ci = std::max(ip - 1, 0); ci <= std::min(ip, t.ni() - 2); ++ci)
    for (int cj = std::max(jp - 1, 0); cj <= std::min(jp, t.nj() - 2); ++cj)
      coarsest = std::max(coarsest, t.leaf_at(ci, cj).level);
  const int levels = std::min(t.max_level(), coarsest + 1);
  const double* xp = c.x() + 3 * p;
  unsigned mask = 0;
  for (int64_t q = 0; q < g.n(); ++q) {
    if (!c.active(q)) continue;
    const double di = (g.i_of(q) - ip) * g.hi, dj = (g.j_of(q) - jp) * g.hj;
    const double rest2 = di * di + dj * dj;
    const double* xq = c.x() + 3 * q;
    double d2 = 0;
    for (int k = 0; k < 3; ++k) d2 += (xq[k] - xp[k]) * (xq[k] - xp[k]);
    for (int l = 1; l <= levels; ++l) {
      const double keep = 1.5 * split(l);
      if (rest2 <= keep * keep) continue;  // the same sheet at this level's reach
      if (d2 < split(l) * split(l)) mask |= 1u << l;
      if (d2 < keep * keep) mask |= 1u << (kKeepFine + l);
    }
  }
  return mask;
}

TEST(AmrcNear, MaskMatchesTheLoopOverEveryPair) {
  constexpr int n = 65, layer = 22;
  constexpr double h = 0.01;
  Simulation w(flat_scene(n, n, (n - 1) * h, (n - 1) * h), test_fabric());
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.3 * h, 0.3 * h);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int lay = std::min(i / layer, 2), u = i - lay * layer;
      const double gap = (1.0 + 12.0 * j / (n - 1)) * h;
      const double y[3] = {(lay % 2 ? layer - u : u) * h + jitter(rng), j * h + jitter(rng),
                           lay * gap + jitter(rng)};
      for (int k = 0; k < 3; ++k) {
        const int64_t v = 3 * (int64_t(i) * n + j) + k;
        w.cloth.z[v] = w.cloth.x1[v] = w.cloth.x2[v] = y[k];
      }
    }
  const double pair = 0.5 * h;
  for (int level = 0; level <= 3; ++level) {
    Amrc amrc(w.cloth, 3, true);
    amrc.restore(std::vector<uint8_t>(size_t(n - 1) * (n - 1), uint8_t(level)));
    amrc.apply(w.cloth, w.fabric.density, w.scene.cloth.shear);
    std::vector<uint32_t> mask(w.cloth.grid.n(), ~0u);
    amrc.near_sheets(w.cloth, pair, {}, mask);
    std::array<int, 2 * kKeepFine> set{};
    int active = 0;
    for (int64_t p = 0; p < w.cloth.grid.n(); ++p) {
      const unsigned want = near_mask_by_pairs(w.cloth, amrc.tree(), pair, p);
      if (w.cloth.active(p)) {
        ASSERT_EQ(mask[p], want) << "level " << level << ", particle " << p;
        ++active;
      }
      for (int b = 0; b < 2 * int(kKeepFine); ++b) set[b] += (want >> b) & 1;
    }
    // Every level the mask holds has its bits set at some particles, clear
    // at others (but level 3's keep reach, 38 h, spans the folded cloth).
    for (int l = 1; l <= std::min(3, level + 1); ++l)
      for (int b : {l, int(kKeepFine) + l}) {
        EXPECT_GT(set[b], 0) << "level " << level << ", bit " << b;
        if (b != int(kKeepFine) + 3) {
          EXPECT_LT(set[b], active) << "level " << level << ", bit " << b;
        }
      }
  }
}

// A cloth draped over a box's edge (grid line i = 3) on level-1 leaves: the
// leaf [2, 4] spans the edge, so its middle particles lie on a chord cutting
// through the box. Refining the leaf next to one of them makes it hang on the
// chord; refining its own leaf then frees it, and it must be lifted out of
// the box (with its velocity) like a particle freed straight from a leaf's
// inside, or the contact throws it out at tens of m/s (the 257 x 257 drape's
// speed spikes at t = 0.32 s, where the sides hit the box's walls).
// A 9 x 9 cloth (spacing h) over the edge of a box whose face is x = 0 and
// top z = 0.4: rows i <= 3 on the top, the rest hanging down the face, all
// at the contact margin and moving with velocity v.
constexpr int kEdgeN = 9, kEdgeRow = 3;
constexpr double kEdgeH = 0.01, kBoxTop = 0.4;

Scene edge_scene() {
  constexpr int n = kEdgeN;
  Scene s = flat_scene(n, n, (n - 1) * kEdgeH, (n - 1) * kEdgeH);
  s.obstacle.shape = ObstacleShape::Box;
  s.obstacle.center = {-0.5, 0.5 * (n - 1) * kEdgeH, kBoxTop - 0.5};
  s.obstacle.size = {1.0, 1.0, 1.0};
  s.solver.contact_thickness = 0.002;  // the chords below cut (h - th) / 2 = 4 mm in
  return s;
}

void drape_over_the_edge(Simulation& w, const double v[3]) {
  constexpr int n = kEdgeN;
  const double th = w.model.contact.thickness, dt = w.cloth.dt_prev;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const bool on_top = i <= kEdgeRow;
      const double y[3] = {on_top ? (i - kEdgeRow) * kEdgeH : th, j * kEdgeH,
                           on_top ? kBoxTop + th : kBoxTop - (i - kEdgeRow) * kEdgeH};
      for (int k = 0; k < 3; ++k) {
        const int64_t u = 3 * (int64_t(i) * n + j) + k;
        w.cloth.z[u] = w.cloth.x1[u] = y[k];
        w.cloth.x2[u] = y[k] - v[k] * dt;
      }
    }
}

TEST(AmrcMesh, ParticlesFreedInsideTheBoxAreLifted) {
  constexpr int n = kEdgeN, edge = kEdgeRow;
  const double v[3] = {0.3, -0.2, -1.0};  // m/s
  Simulation w(edge_scene(), test_fabric());
  drape_over_the_edge(w, v);
  const Contact& contact = w.model.contact;
  const Scene& s = w.scene;
  const double th = contact.thickness, dt = w.cloth.dt_prev;
  Amrc amrc(w.cloth, 1);
  std::vector<uint8_t> levels(size_t(n - 1) * (n - 1), 1);
  amrc.set_levels(w.cloth, w.fabric.density, s.cloth.shear, levels);
  amrc.fill_inactive(w.cloth);  // the odd particles onto their leaves' surfaces
  const int64_t p = int64_t(edge) * n + 2;  // on the side shared by leaves [2,4]x[0,2] and [2,4]x[2,4]
  ASSERT_LT(clearance(contact.obstacle, w.cloth.x() + 3 * p), -0.5 * th) << "the chord should cut the box";
  auto refine = [&](int cj0) {  // the level-1 leaf [2,4] x [cj0, cj0 + 2] to the finest
    for (int ci = 2; ci < 4; ++ci)
      for (int cj = cj0; cj < cj0 + 2; ++cj) levels[size_t(ci) * (n - 1) + cj] = 0;
    amrc.set_levels(w.cloth, w.fabric.density, s.cloth.shear, levels);
    amrc.lift_new_particles(w.cloth, contact);
  };
  refine(0);
  ASSERT_TRUE(w.cloth.flags[p] & kHanging) << "the particle should hang on the coarse side first";
  refine(2);
  ASSERT_TRUE(w.cloth.free(p));
  for (int64_t q = 0; q < w.cloth.grid.n(); ++q) {
    if (!w.cloth.free(q)) continue;
    EXPECT_GE(clearance(contact.obstacle, w.cloth.x() + 3 * q), th * (1 - 1e-9)) << "particle " << q;
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(w.cloth.x1[3 * q + k] - w.cloth.x2[3 * q + k], v[k] * dt, 1e-12) << "particle " << q;
  }
}

// With the box given, a cloth that is flat on either side of the edge
// coarsens there but not across the edge: the level-1 cells spanning it
// would cut 4 mm into the box. Without it, everything merges.
TEST(AmrcMesh, LeavesOverTheBoxEdgeStaySplit) {
  const double still[3] = {0, 0, 0};
  for (bool box : {true, false}) {
    Simulation w(edge_scene(), test_fabric());
    drape_over_the_edge(w, still);
    Amrc amrc(w.cloth, 2);
    const Thresholds flat_everywhere{10.0, 5.0};  // no turn is sharp enough to split
    for (int pass = 0; pass < 4; ++pass)
      amrc.adapt(w.cloth, w.fabric.density, w.scene.cloth.shear, flat_everywhere, {},
                 box ? &w.model.contact.obstacle : nullptr);
    const Quadtree& t = amrc.tree();
    ASSERT_TRUE(t.balanced());
    for (int ci = 0; ci < kEdgeN - 1; ++ci)
      for (int cj = 0; cj < kEdgeN - 1; ++cj) {
        const int l = t.leaf_at(ci, cj).level;
        if (!box) {
          EXPECT_EQ(l, 2) << ci << "," << cj;
        } else if (ci == 2 || ci == 3) {
          EXPECT_EQ(l, 0) << ci << "," << cj << ": across the edge";
        } else {
          EXPECT_EQ(l, 1) << ci << "," << cj << ": beside the edge (2:1 with it)";
        }
      }
  }
}

}  // namespace
}  // namespace drape::test

namespace drape::test {
namespace {

// Grid sequencing's first mesh: the coarsest within the spacing, keeping at
// least 8 intervals per side.
TEST(GridSequence, StartLevelFromTheSpacing) {
  auto level = [](int n, double size, double spacing) {
    Grid g;
    g.ni = g.nj = n;
    g.hi = g.hj = size / (n - 1);
    return sequence_start_level(g, spacing);
  };
  EXPECT_EQ(level(1000, 1.0, 0.04), 5);  // h = 1 mm: 32 mm leaves
  EXPECT_EQ(level(1000, 1.0, 0.0), 0);
  EXPECT_EQ(level(257, 1.0, 0.04), 3);   // 3.9 mm -> 31 mm
  EXPECT_EQ(level(49, 1.0, 0.04), 0);    // 20.8 mm: one level up is already too coarse
  EXPECT_EQ(level(17, 1.0, 10.0), 1);    // 16 intervals: 8 per side at level 1, no further
}

// The next finer mesh's wall time: 8 times the last stage's at least (4
// times the particles, twice the iterations), more when the last refinement
// grew the time more. The default run: 22 s on level 5, 88 s on level 4
// (4.0x), 430 s left, and the 127 x 127 mesh still moving after 426 s.
TEST(GridSequence, NextStageGrowsAsTheLastRefinementDid) {
  const auto jacobi = [](double s) { return StageTime{s, false}; };
  EXPECT_DOUBLE_EQ(next_stage_seconds(jacobi(10), {}, false), 80);  // the first stage: particles and iterations
  EXPECT_DOUBLE_EQ(next_stage_seconds(jacobi(10), jacobi(5), false), 80);          // grew 2x: still the floor
  EXPECT_DOUBLE_EQ(next_stage_seconds(jacobi(99), jacobi(9), false), 99 * 11.0);  // grew 11x: that growth again
  EXPECT_GT(next_stage_seconds(jacobi(87.6), jacobi(21.9), false), 430);          // what the default run had left
}

// The next stage's preconditioner sets the floor; a growth seen under
// another preconditioner does not carry over.
TEST(GridSequence, NextStageKnowsItsPreconditioner) {
  const StageTime j{10, false}, m{10, true};
  EXPECT_DOUBLE_EQ(next_stage_seconds(j, {}, true), 10 * kMultigridStageGrowth);
  EXPECT_DOUBLE_EQ(next_stage_seconds(m, StageTime{0.5, true}, true), 200);       // grew 20x: again
  EXPECT_DOUBLE_EQ(next_stage_seconds(m, StageTime{1, false}, true), 10 * kMultigridStageGrowth);
  EXPECT_DOUBLE_EQ(next_stage_seconds(j, StageTime{1, false}, true), 10 * kMultigridStageGrowth);
  // What the default run had left after level 4 (62.9 s; level 5 16.0 s):
  // its level 3 did not come to rest in it.
  EXPECT_GT(next_stage_seconds(StageTime{62.9, true}, StageTime{16.0, true}, true), 461);
  Grid g;
  g.ni = g.nj = 1000;
  EXPECT_EQ(uniform_level_particles(g, 5), 33 * 33);
  EXPECT_EQ(uniform_level_particles(g, 4), 64 * 64);
  EXPECT_EQ(uniform_level_particles(g, 0), 1000 * 1000);
}


// `auto`: Jacobi below solver.multigrid_particles, the multigrid from it on;
// the explicit choices stay.
TEST(GridSequence, AutoPreconditionerFromAMeshSize) {
  SolverSpec s;
  s.preconditioner = Preconditioner::Auto;
  s.multigrid_particles = 4096;
  EXPECT_EQ(stage_preconditioner(s, 4095), Preconditioner::Jacobi);
  EXPECT_EQ(stage_preconditioner(s, 4096), Preconditioner::Multigrid);
  const SolverSpec mg = stage_solver(s, 4096), j = stage_solver(s, 4095);
  EXPECT_EQ(mg.dt_max, s.multigrid_dt_max);
  EXPECT_EQ(mg.max_iterations, s.multigrid_max_iterations);
  EXPECT_EQ(j.dt_max, s.dt_max);
  EXPECT_EQ(j.max_iterations, s.max_iterations);
  s.preconditioner = Preconditioner::Jacobi;
  EXPECT_EQ(stage_preconditioner(s, 1 << 20), Preconditioner::Jacobi);
  s.preconditioner = Preconditioner::Multigrid;
  EXPECT_EQ(stage_preconditioner(s, 1), Preconditioner::Multigrid);
  EXPECT_EQ(stage_solver(s, 1).dt_max, s.dt_max);  // explicit: the scene's own settings
}

// A split's stretched edges: eased to 1 % strain, the others untouched, and
// back at the material's rest length after strain / rate seconds, no sooner.
TEST(GridSequence, StretchedEdgesEaseBackToTheirRestLength) {
  Scene s = flat_scene(9, 9, 0.08, 0.08);  // h = 1 cm
  Simulation w(s, test_fabric());
  Cloth& c = w.cloth;
  const double h = c.grid.hi;
  const int64_t p = c.grid.id(4, 4);
  c.z[3 * p + 2] += 0.75 * h;  // its four edges: sqrt(1 + 0.75^2) = 1.25, 25 % strain
  Evaluator& ev = w.loop->evaluator();
  const double worst = ease_stretched_edges(c, ev);
  EXPECT_NEAR(worst, 0.25, 1e-12);
  const int64_t left = 2 * c.grid.id(3, 4), right = 2 * p, far = 2 * c.grid.id(0, 0);
  for (int64_t e : {left, right}) EXPECT_NEAR(ev.edge_rest(e), 1.25 * h / 1.01, 1e-12) << "edge " << e;
  EXPECT_DOUBLE_EQ(ev.edge_rest(far), h);
  const double rate = 2.0, dt = 1e-3;
  int steps = 0;
  while (ev.edge_rest(right) > h && steps < 1000) {
    relax_eased_edges(c, ev, rate, dt);
    ++steps;
  }
  EXPECT_DOUBLE_EQ(ev.edge_rest(right), h);
  EXPECT_DOUBLE_EQ(ev.edge_rest(left), h);
  EXPECT_EQ(steps, int(std::ceil((1.25 / 1.01 - 1) / (rate * dt) - 1e-9)));
  EXPECT_DOUBLE_EQ(ev.edge_rest(far), h);
  // A list change (a next stage's) lays the mesh's rest lengths out again.
  ease_stretched_edges(c, ev);
  build_active_lists(c, w.tiling, w.owned(), w.lists);
  ev.edge_rest_lengths();
  EXPECT_DOUBLE_EQ(ev.edge_rest(right), h);
}

// On an AMRC mesh the evaluator's triples' rest lengths and cells' areas,
// computed from the neighbours it holds in list order, are the mesh's to the
// bit (topology.hpp), at every listed element.
TEST(AmrcMesh, EvaluatorRestGeometryIsTheMeshs) {
  Simulation w(flat_scene(13, 11, 0.12, 0.10), test_fabric());
  w.set_tree(mixed_tree());
  w.rebuild();
  const Cloth& c = w.cloth;
  Evaluator& ev = w.loop->evaluator();
  ev.edge_rest_lengths();  // lays the rows out for the lists now
  int64_t triples = 0, cells = 0;
  for (int64_t s : w.lists.triples.items) {
    EXPECT_EQ(ev.triple_rest_of(s), triple_rest_geometry(c, s).rest) << "triple slot " << s;
    ++triples;
  }
  for (int64_t s : w.lists.shears.items) {
    EXPECT_EQ(ev.cell_area_of(s), cell_area(c, s)) << "cell slot " << s;
    ++cells;
  }
  EXPECT_GT(triples, 0);
  EXPECT_LT(cells, 120) << "the mesh should have coarse leaves";
  EXPECT_GT(cells, 0);
}

// Uniform levels keep the finest mesh's mass, and every finer mesh starts on
// the coarser one's surface with its forces: an affine cloth stays affine,
// a uniform tension stays uniform, through levels 2, 1 and 0.
TEST(GridSequence, UniformLevelsCarryTheState) {
  Scene s = flat_scene(19, 23, 0.18, 0.22);
  Simulation w(s, test_fabric());
  Cloth& c = w.cloth;
  const double mass = c.total_mass();
  auto affine = [&](int64_t p, int a) {
    const double i = c.grid.i_of(p), j = c.grid.j_of(p);
    const double row[3][3] = {{0.01, 0.002, 0.1}, {-0.003, 0.012, 0.2}, {0.004, -0.005, 0.45}};
    return row[a][0] * i + row[a][1] * j + row[a][2];
  };
  Amrc amrc(c, 2);
  amrc.set_uniform_level(c, w.fabric.density, s.cloth.shear, 2);
  int64_t coarse = 0;
  for (int64_t p = 0; p < c.grid.n(); ++p) {
    if (!c.active(p)) continue;
    ++coarse;
    for (int a = 0; a < 3; ++a) c.z[3 * p + a] = c.x1[3 * p + a] = c.x2[3 * p + a] = affine(p, a);
    for (int d = 0; d < 2; ++d)
      if (c.edge_on[2 * p + d]) c.z[c.layout.tension() + 2 * p + d] = 7.0;
  }
  EXPECT_EQ(coarse, 6 * 7) << "18 x 22 intervals in leaves of 4 (clipped at the far sides)";
  EXPECT_NEAR(c.total_mass(), mass, 1e-12 * mass);
  for (int level : {1, 0}) {
    amrc.set_uniform_level(c, w.fabric.density, s.cloth.shear, level);
    EXPECT_NEAR(c.total_mass(), mass, 1e-12 * mass) << "level " << level;
    for (int64_t p = 0; p < c.grid.n(); ++p) {
      if (!c.active(p)) continue;
      for (int a = 0; a < 3; ++a) {
        ASSERT_NEAR(c.z[3 * p + a], affine(p, a), 1e-12) << "level " << level << ", particle " << p;
        ASSERT_NEAR(c.x1[3 * p + a], affine(p, a), 1e-12);
      }
      for (int d = 0; d < 2; ++d)
        if (c.edge_on[2 * p + d]) {
          ASSERT_EQ(c.z[c.layout.tension() + 2 * p + d], 7.0) << "level " << level;
        }
    }
  }
  for (int64_t p = 0; p < c.grid.n(); ++p) ASSERT_TRUE(c.active(p)) << "level 0 is the finest mesh";
}

}  // namespace
}  // namespace drape::test
