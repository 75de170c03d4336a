// Shear read per cell (kernels.hpp shear_cell): the cells are the leaves of
// the active mesh, a uniform shear reads alike in each, an in-plane zigzag of
// the mesh lines shears every cell (the per-particle cross let it pass), and
// AMRC carries the cells' shear forces across split and merge.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <random>

#include "amrc/amrc.hpp"
#include "mesh/topology.hpp"
#include "solver/shear_cell.hpp"
#include "support/scenes.hpp"

namespace drape::test {
namespace {

// 13 x 11 particles, on the finest mesh or on mixed_tree's leaves.
std::unique_ptr<Simulation> mixed_world(bool amrc) {
  auto w = std::make_unique<Simulation>(flat_scene(13, 11, 0.12, 0.10), test_fabric());
  if (!amrc) return w;
  w->set_tree(mixed_tree());
  w->rebuild();
  return w;
}

int64_t leaf_count(const Simulation& w) {
  if (!w.tree()) return int64_t(w.cloth.grid.ni - 1) * (w.cloth.grid.nj - 1);
  int64_t n = 0;
  w.tree()->for_each_leaf([&](const Cell&) { ++n; });
  return n;
}

class ShearCells : public ::testing::TestWithParam<bool> {};

TEST_P(ShearCells, AreTheLeavesAndTileTheCloth) {
  const auto world = mixed_world(GetParam());
  const Simulation& w = *world;
  const Cloth& c = w.cloth;
  int64_t on = 0;
  double area = 0;
  for (int64_t s = 0; s < c.grid.n(); ++s) {
    if (!c.shear_on[s]) continue;
    ++on;
    area += cell_area(c, s);
    int64_t ids[4];
    shear_cell(c, s, ids);
    for (int k = 0; k < 3; ++k) {
      ASSERT_TRUE(c.active(ids[k + 1])) << "slot " << s << " corner " << k + 1;
      EXPECT_EQ(c.corner_of[k][ids[k + 1]], s) << "corner " << k + 1 << " of slot " << s;
    }
    EXPECT_EQ(c.grid.j_of(ids[1]), c.grid.j_of(s)) << "corner 1 lies along i from slot " << s;
    EXPECT_EQ(c.grid.i_of(ids[2]), c.grid.i_of(s)) << "corner 2 lies along j from slot " << s;
    EXPECT_EQ(ids[3], ids[1] + (ids[2] - s)) << "corner 3 closes the cell of slot " << s;
  }
  if (GetParam()) {
    EXPECT_LT(on, 120) << "the AMRC mesh should have coarse leaves";
  }
  EXPECT_EQ(on, leaf_count(w));
  EXPECT_NEAR(area, 0.12 * 0.10, 1e-15);
  for (int64_t p = 0; p < c.grid.n(); ++p)
    for (int k = 0; k < 3; ++k) {
      const int64_t s = c.corner_of[k][p];
      if (s >= 0) {
        EXPECT_EQ(c.cell[k][s], p) << "corner " << k + 1 << " of slot " << s;
      }
    }
}

// x += tan(gamma) y shears every corner of every cell by gamma exactly,
// whatever the cell's size.
TEST_P(ShearCells, AUniformShearReadsTheSameInEveryCell) {
  const auto world = mixed_world(GetParam());
  Simulation& w = *world;
  Cloth& c = w.cloth;
  const double gamma = 0.2;
  for (int64_t p = 0; p < c.grid.n(); ++p) c.z[3 * p] += std::tan(gamma) * c.z[3 * p + 1];
  for (int64_t s = 0; s < c.grid.n(); ++s) {
    if (!c.shear_on[s]) continue;
    const CellAt a = cell_at(c, c.z.data(), s);
    V3<double> g[4];
    EXPECT_NEAR(shear_cell(a.x, g), gamma, 1e-12) << "slot " << s;
  }
}

// The evaluator holds no triple's rest length nor cell's area: it computes
// them from the neighbours it keeps in list order (a triple's previous and
// next particles, a cell's corners 1 and 2). They must be the mesh's to the
// bit, on coarse leaves too, or the states' checksums move.
TEST_P(ShearCells, RestGeometryFromTheNeighboursAlone) {
  const auto world = mixed_world(GetParam());
  const Cloth& c = world->cloth;
  const Grid& g = c.grid;
  int64_t triples = 0;
  for (int64_t s = 0; s < 2 * g.n(); ++s) {
    if (!c.triple_on[s]) continue;
    ++triples;
    const int d = int(s & 1);
    const int64_t p = s >> 1;
    const double rest = triple_rest_length(g, d, c.prev_at(d, p), p, c.next_at(d, p));
    EXPECT_EQ(rest, triple_rest_geometry(c, s).rest) << "triple slot " << s;
    // Half the gaps to both neighbours: the spacing on the finest mesh.
    EXPECT_NEAR(rest, 0.5 * double(c.next_at(d, p) - c.prev_at(d, p)) / g.stride(d) * g.h(d), 1e-15) << s;
  }
  EXPECT_GT(triples, 0);
  for (int64_t s = 0; s < g.n(); ++s) {
    if (!c.shear_on[s]) continue;
    const double area = cell_area(g, s, c.cell_at(0, s), c.cell_at(1, s));
    EXPECT_EQ(area, cell_area(c, s)) << "cell slot " << s;
    // The leaf's sides along i and j.
    const double sides = (g.i_of(c.cell_at(0, s)) - g.i_of(s)) * g.hi * ((g.j_of(c.cell_at(1, s)) - g.j_of(s)) * g.hj);
    EXPECT_NEAR(area, sides, 1e-15) << "cell slot " << s;
  }
}

INSTANTIATE_TEST_SUITE_P(FinestAndAmrc, ShearCells, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? "amrc" : "finest"; });

// The warp lines kinked in the cloth's plane, y += delta (-1)^i: each
// particle's four quadrants shear alternately and their mean is zero (the
// hourglass of the per-particle cross), but every cell shears by
// atan(2 delta / h), with the sign alternating along i.
TEST(ShearCell, AnInPlaneZigzagShearsEveryCell) {
  const auto world = mixed_world(false);
  Simulation& w = *world;
  Cloth& c = w.cloth;
  const double delta = 0.1 * c.grid.hi;
  for (int64_t p = 0; p < c.grid.n(); ++p) c.z[3 * p + 1] += c.grid.i_of(p) % 2 ? -delta : delta;
  int64_t cells = 0;
  for (int64_t s = 0; s < c.grid.n(); ++s) {
    if (!c.shear_on[s]) continue;
    const CellAt a = cell_at(c, c.z.data(), s);
    V3<double> g[4];
    const double sign = c.grid.i_of(s) % 2 ? 1.0 : -1.0;
    EXPECT_NEAR(shear_cell(a.x, g), sign * std::atan(2 * delta / c.grid.hi), 1e-12) << "slot " << s;
    ++cells;
  }
  EXPECT_EQ(cells, 12 * 10);
}

// Shear forces are per unit width: a split leaf's children keep the parent's,
// and a merged parent takes the mean of its children's.
// The cell's angle from one atan2 of the corners' product (shear_cell) is
// the mean of the four corners' own atan2 angles, on cells from slightly to
// strongly sheared and folded (where a pair's difference passes pi/2 and
// each pair takes its own atan2).
TEST(ShearCell, OneArgumentIsTheMeanOfTheCornerAngles) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  int fallbacks = 0;
  for (int sample = 0; sample < 2000; ++sample) {
    const double amount = sample < 1000 ? 0.1 : 0.9, h = 1e-3;
    V3<double> x[4];
    const double at[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    for (int k = 0; k < 4; ++k)
      x[k] = {h * (at[k][0] + amount * u(rng)), h * (at[k][1] + amount * u(rng)), h * amount * u(rng)};
    double mean = 0, pr = 1, qr = 1;
    double s[4], co[4];
    for (const ShearCorner& q : kShearCorners) {
      V3<double> g[3];
      shear_terms(x[q.c], x[q.a], x[q.b], g, s[q.c], co[q.c]);
      mean += 0.25 * q.sign * std::atan2(co[q.c], s[q.c]);
    }
    pr = s[0] * s[1] + co[0] * co[1];
    qr = s[3] * s[2] + co[3] * co[2];
    fallbacks += !(pr > 0 && qr > 0);
    V3<double> g[4];
    EXPECT_NEAR(shear_cell(x, g), mean, 1e-14) << "sample " << sample;
  }
  EXPECT_GT(fallbacks, 0) << "no cell took each pair's own atan2";
}

// The lanes' kernels (shear_cell on doubles, shear_cell_hv: the four
// corners side by side) give the scalar kernels' numbers bit for bit: the
// angle, the gradient and H r, on cells from slightly to strongly sheared
// and folded, at the finest mesh's scale and a coarse one's.
TEST(ShearLanes, CellAndHessianVectorAreTheScalarKernelsBitForBit) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  auto same = [](const V3<double>* a, const V3<double>* b) { return std::memcmp(a, b, 4 * sizeof(V3<double>)) == 0; };
  for (int sample = 0; sample < 3000; ++sample) {
    const double amount = sample % 3 == 0 ? 0.05 : sample % 3 == 1 ? 0.4 : 0.9;
    const double h = sample % 2 ? 1e-3 : 3e-2;
    V3<double> x[4], r[4];
    const double at[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    for (int k = 0; k < 4; ++k) {
      x[k] = {h * (at[k][0] + amount * u(rng)), h * (at[k][1] + amount * u(rng)), h * amount * u(rng)};
      r[k] = {u(rng), u(rng), u(rng)};
    }
    V3<double> g[4], gs[4], hr[4], grs[4], hrs[4];
    const double phi = shear_cell(x, g), phis = shear_cell_scalar<double>(x, gs);
    ASSERT_EQ(std::memcmp(&phi, &phis, sizeof phi), 0) << "sample " << sample;
    ASSERT_TRUE(same(g, gs)) << "sample " << sample;
    shear_cell<double, false>(x, g);
    ASSERT_TRUE(same(g, gs)) << "sample " << sample;
    shear_cell_hv(x, r, g, hr);
    shear_cell_hv_scalar(x, r, grs, hrs);
    ASSERT_TRUE(same(g, grs) && same(g, gs)) << "sample " << sample;
    ASSERT_TRUE(same(hr, hrs)) << "sample " << sample;
  }
}

#if DRAPE_LANES
// Four cells' gradients and angles from shear_cell_terms and
// shear_angles_four (the cost pass's cells four at a time) are shear_cell's,
// bit for bit: groups whose cells all take the one-atan2 form (in lanes)
// and groups where a strongly sheared cell takes the pairwise form.
TEST(ShearLanes, FourCellsAnglesAreShearCellsBitForBit) {
  std::mt19937_64 rng(6);
  std::uniform_real_distribution<double> u(-1, 1);
  const double at[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  int lanes = 0, pairwise = 0;
  for (int sample = 0; sample < 4000; ++sample) {
    V3<double> x[4][4], g[4][4];
    double sn[4][4], co[4][4], phi[4];
    for (int l = 0; l < 4; ++l) {
      const double amount = (sample + l) % 3 == 0 ? 0.05 : (sample + l) % 3 == 1 ? 0.4 : sample % 5 == 0 ? 1.6 : 0.9;
      const double h = (sample + l) % 2 ? 1e-3 : 3e-2;
      for (int k = 0; k < 4; ++k)
        x[l][k] = {h * (at[k][0] + amount * u(rng)), h * (at[k][1] + amount * u(rng)), h * amount * u(rng)};
      shear_cell_terms(x[l], g[l], sn[l], co[l]);
    }
    shear_angles_four(sn, co, phi);
    bool one = true;
    for (int l = 0; l < 4; ++l) {
      V3<double> g1[4];
      const double phi1 = shear_cell(x[l], g1);
      ASSERT_EQ(std::memcmp(&phi[l], &phi1, sizeof phi1), 0) << "sample " << sample << " cell " << l;
      ASSERT_EQ(std::memcmp(g[l], g1, sizeof g1), 0) << "sample " << sample << " cell " << l;
      const double pr = sn[l][0] * sn[l][1] + co[l][0] * co[l][1], qr = sn[l][3] * sn[l][2] + co[l][3] * co[l][2];
      one = one && pr > 0 && qr > 0;
    }
    (one ? lanes : pairwise) += 1;
  }
  EXPECT_GT(lanes, 1000);
  EXPECT_GT(pairwise, 50);
}

// Four cells' gradients and H r side by side (shear_cells_hv_four, the
// gradient pass's cells four at a time) are shear_cell_hv_scalar's, bit for
// bit, cell by cell: cells from slightly to strongly sheared and folded, at
// the finest mesh's scale and a coarse one's, zero moves among them (a fixed
// corner's residual).
TEST(ShearLanes, FourCellsHessianVectorIsTheScalarKernelsBitForBit) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  const double at[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  for (int sample = 0; sample < 3000; ++sample) {
    V3<double> x[4][4], r[4][4], g[4][4], hr[4][4];
    for (int l = 0; l < 4; ++l) {
      const double amount = (sample + l) % 3 == 0 ? 0.05 : (sample + l) % 3 == 1 ? 0.4 : 0.9;
      const double h = (sample + l) % 2 ? 1e-3 : 3e-2;
      for (int k = 0; k < 4; ++k) {
        x[l][k] = {h * (at[k][0] + amount * u(rng)), h * (at[k][1] + amount * u(rng)), h * amount * u(rng)};
        r[l][k] = (sample + k) % 7 == 0 ? V3<double>{0, 0, 0} : V3<double>{u(rng), u(rng), u(rng)};
      }
    }
    shear_cells_hv_four(x, r, g, hr);
    for (int l = 0; l < 4; ++l) {
      V3<double> g1[4], hr1[4];
      shear_cell_hv_scalar(x[l], r[l], g1, hr1);
      ASSERT_EQ(std::memcmp(g[l], g1, sizeof g1), 0) << "sample " << sample << " cell " << l;
      ASSERT_EQ(std::memcmp(hr[l], hr1, sizeof hr1), 0) << "sample " << sample << " cell " << l;
    }
  }
}

// store_fours12 lays four elements' four 3-vectors out element after
// element (the gradient pass's buffer entries).
TEST(ShearLanes, StoreFoursLaysOutElementAfterElement) {
  V4 v[4];
  for (int k = 0; k < 4; ++k)
    for (int l = 0; l < 4; ++l) {
      v[k].x[l] = 100 * l + 3 * k;
      v[k].y[l] = 100 * l + 3 * k + 1;
      v[k].z[l] = 100 * l + 3 * k + 2;
    }
  double out[48];
  store_fours12(v, out);
  for (int l = 0; l < 4; ++l)
    for (int j = 0; j < 12; ++j) EXPECT_EQ(out[12 * l + j], 100 * l + j) << "element " << l << " double " << j;
}
#endif

TEST(ShearCell, AmrcCarriesTheForceAcrossSplitAndMerge) {
  Scene s = flat_scene(9, 9, 0.08, 0.08);
  Simulation w(s, test_fabric());
  Cloth& c = w.cloth;
  Amrc amrc(c, 1);
  amrc.set_uniform_level(c, w.fabric.density, true, 1);
  double* f = c.shear();
  for (int64_t p = 0; p < c.grid.n(); ++p)
    if (c.shear_on[p]) f[p] = 1.0 + 0.1 * double(p);
  const std::vector<double> parent(f, f + c.grid.n());
  amrc.set_uniform_level(c, w.fabric.density, true, 0);
  for (int64_t p = 0; p < c.grid.n(); ++p) {
    if (!c.shear_on[p]) continue;
    const int i = c.grid.i_of(p) & ~1, j = c.grid.j_of(p) & ~1;
    ASSERT_EQ(f[p], parent[c.grid.id(i, j)]) << "finest cell " << p << " keeps its parent's force";
  }
  for (int64_t p = 0; p < c.grid.n(); ++p)
    if (c.shear_on[p]) f[p] = double(c.grid.i_of(p) % 2) + 2.0 * double(c.grid.j_of(p) % 2);
  amrc.set_uniform_level(c, w.fabric.density, true, 1);
  int64_t merged = 0;
  for (int64_t p = 0; p < c.grid.n(); ++p) {
    if (!c.shear_on[p]) continue;
    EXPECT_DOUBLE_EQ(f[p], (0 + 1 + 2 + 3) / 4.0) << "merged cell " << p << " takes its children's mean";
    ++merged;
  }
  EXPECT_EQ(merged, 16);
}

}  // namespace
}  // namespace drape::test
