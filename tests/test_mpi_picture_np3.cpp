// The picture and the drape test on three ranks: rank 0 draws from the
// samples' positions their owners send, and counts the or of the ranks'
// shadow rasters. Each must equal what one rank computes from whole arrays,
// bit for bit, and the picture's gather must bring rank 0 a small part of
// the cloth, not all of it. Runs under mpiexec -n 3.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "app/picture_samples.hpp"
#include "decomp/gather.hpp"
#include "io/output.hpp"
#include "io/picture.hpp"
#include "mesh/tiles.hpp"
#include "solver/drape_coefficient.hpp"
#include "solver/model.hpp"
#include "support/files.hpp"
#include "support/scenes.hpp"

namespace drape::test {
namespace {

int my_rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

// Tiles dealt out unevenly, so that every rank's tiles are scattered.
std::vector<int> scattered_owners(const Tiling& tl) {
  std::vector<int> owner(tl.count());
  for (int t = 0; t < tl.count(); ++t) owner[t] = (7 * t + t / 5) % 3;
  return owner;
}

// A wavy cloth of ni x nj with holes: a band of rows across it where only
// every 8th row has active particles, every 8th, staggered from row to row
// (their rows fill first, then the inactive rows between them along the
// samples' columns, from two rows' different brackets), and the corners
// outside an inscribed ellipse (nothing brackets those).
struct Sheet {
  int ni, nj;
  std::vector<double> x;
  std::vector<uint8_t> flags;
};

Sheet wavy_sheet(int ni, int nj) {
  Sheet s{ni, nj, std::vector<double>(3 * size_t(ni) * nj), std::vector<uint8_t>(size_t(ni) * nj, 0)};
  for (int i = 0; i < ni; ++i)
    for (int j = 0; j < nj; ++j) {
      const size_t p = size_t(i) * nj + j;
      s.x[3 * p] = 1e-3 * i;
      s.x[3 * p + 1] = 1e-3 * j;
      s.x[3 * p + 2] = 0.05 * std::sin(0.013 * i) * std::cos(0.021 * j) + 0.2;
      const double u = (i - 0.5 * ni) / (0.5 * ni), v = (j - 0.5 * nj) / (0.5 * nj);
      const bool coarse = i >= 200 && i < 440;
      const bool active = u * u + v * v <= 1.0 && (!coarse || (i % 8 == 0 && (j + 3 * (i / 8)) % 8 == 0));
      s.flags[p] = active ? kActive : 0;
    }
  return s;
}

TEST(PictureNp3, SamplesFromOwnersEqualWholeArrays) {
  const Sheet sheet = wavy_sheet(801, 701);
  const Tiling tl(sheet.ni, sheet.nj, 50);
  const std::vector<int> owner = scattered_owners(tl);
  // Each rank holds its own tiles' positions; the rest are NaN, so a sample
  // read from anywhere else would spoil the picture.
  std::vector<double> mine(sheet.x.size(), std::numeric_limits<double>::quiet_NaN());
  for (size_t p = 0; p < sheet.flags.size(); ++p)
    if (owner[tl.tile_of(int64_t(p))] == my_rank())
      for (int c = 0; c < 3; ++c) mine[3 * p + c] = sheet.x[3 * p + c];
  const PicturePlan plan = plan_picture(sheet.ni, sheet.nj, sheet.flags.data());
  PictureSurface many;
  size_t received = 0;
  ASSERT_TRUE(picture_samples_on_root(plan, mine.data(), tl, owner, MPI_COMM_WORLD, many, &received));
  if (my_rank() != 0) return;
  // The whole cloth would be 3 x 801 x 701 values; the samples (268 x 235)
  // and their brackets are about a tenth of them.
  EXPECT_EQ(received, 3 * plan.needed.size());
  EXPECT_LT(double(received), 0.15 * double(sheet.x.size()));
  FrameView whole;
  whole.ni = sheet.ni;
  whole.nj = sheet.nj;
  whole.x = sheet.x.data();
  whole.flags = sheet.flags.data();
  const PictureSurface one = picture_surface(whole);
  ASSERT_EQ(one.mi, many.mi);
  ASSERT_EQ(one.mj, many.mj);
  EXPECT_EQ(one.ok, many.ok);
  EXPECT_EQ(0, std::memcmp(one.x.data(), many.x.data(), one.x.size() * sizeof(double)));
  size_t drawn = 0, filled = 0;
  for (size_t k = 0; k < one.ok.size(); ++k) {
    drawn += one.ok[k];
    const size_t p = size_t(plan.rows[k / one.mj]) * sheet.nj + plan.cols[k % one.mj];
    filled += one.ok[k] && !sheet.flags[p];
  }
  EXPECT_GT(filled, 1000u) << "the sheet's holes should need filling";
  EXPECT_LT(drawn, one.ok.size()) << "the corners should stay undrawn";
  const std::string dir = DRAPE_TEST_TMP;
  ObstacleSpec none;
  none.shape = ObstacleShape::None;
  render_picture(whole, none, dir + "/np3_whole.png", 320, 240);
  render_picture(many, none, dir + "/np3_samples.png", 320, 240);
  EXPECT_EQ(slurp(dir + "/np3_whole.png"), slurp(dir + "/np3_samples.png"));
}

// A position a sample reads that is not finite: every rank is told, and
// the caller falls back on the whole cloth.
TEST(PictureNp3, NonFiniteSampleIsEveryRanksFallback) {
  Sheet sheet = wavy_sheet(101, 91);
  const Tiling tl(sheet.ni, sheet.nj, 20);
  const std::vector<int> owner = scattered_owners(tl);
  const PicturePlan plan = plan_picture(sheet.ni, sheet.nj, sheet.flags.data());
  sheet.x[3 * plan.needed[plan.needed.size() / 2] + 2] = std::numeric_limits<double>::infinity();
  PictureSurface s;
  EXPECT_FALSE(picture_samples_on_root(plan, sheet.x.data(), tl, owner, MPI_COMM_WORLD, s));
  EXPECT_EQ(s.mi, 0);
}

// The Cusick scene's specimen, sagging over the disc's rim in six folds.
TEST(PictureNp3, DrapeFiguresFromOredCoversEqualOneRanks) {
  Scene s;
  s.cloth.particles = {65, 65};
  s.cloth.size = {0.3, 0.3};
  s.cloth.shape = ClothShape::Disc;
  s.cloth.tile = 16;
  s.obstacle.shape = ObstacleShape::Disc;
  s.obstacle.center = {0.0, 0.0, 0.195};
  s.obstacle.size = {0.18, 0.18, 0.01};
  s.obstacle.radius = 0.09;
  const Cloth c = make_cloth(s, test_fabric());
  std::vector<double> x(c.x(), c.x() + 3 * c.grid.n());
  for (int64_t p = 0; p < c.grid.n(); ++p) {
    const double r = std::hypot(x[3 * p], x[3 * p + 1]), a = std::atan2(x[3 * p + 1], x[3 * p]);
    if (r <= 0.09) continue;
    const double r2 = 0.09 + (r - 0.09) * 0.6 * (1 + 0.3 * std::cos(6 * a));
    x[3 * p] *= r2 / r;
    x[3 * p + 1] *= r2 / r;
  }
  const Tiling tl(c.grid.ni, c.grid.nj, s.cloth.tile);
  const std::vector<int> owner = scattered_owners(tl);
  std::vector<int> tiles;
  for (int t = 0; t < tl.count(); ++t)
    if (owner[t] == my_rank()) tiles.push_back(t);
  DrapeCover cover = drape_cover(c, x.data(), s, tl, tiles);
  or_on_root(cover.shadow, MPI_COMM_WORLD);
  or_on_root(cover.specimen, MPI_COMM_WORLD);
  if (my_rank() != 0) return;
  const DrapeTest many = drape_figures(c, s, cover), one = drape_test(c, x.data(), s);
  EXPECT_GT(one.coefficient, 0.3);
  EXPECT_LT(one.coefficient, 0.95);
  EXPECT_EQ(one.nodes, 6);
  EXPECT_EQ(0, std::memcmp(&one.coefficient, &many.coefficient, sizeof(double)));
  EXPECT_EQ(0, std::memcmp(&one.shadow, &many.shadow, sizeof(double)));
  EXPECT_EQ(0, std::memcmp(&one.specimen, &many.specimen, sizeof(double)));
  EXPECT_EQ(one.nodes, many.nodes);
}

}  // namespace
}  // namespace drape::test
