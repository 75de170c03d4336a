// Two ranks: sums over tiles and the state checksum are bitwise those of one
// rank, whichever rank owns which tile. Partials are chosen so that any other
// summation order gives a different double.
#include <gtest/gtest.h>
#include <mpi.h>

#include "decomp/collective.hpp"
#include "decomp/reduction.hpp"
#include "solver/checksum.hpp"
#include "support/scenes.hpp"

namespace drape::test {
namespace {

int rank() { return rank_of(MPI_COMM_WORLD); }

// Tile t's partial: order-sensitive magnitudes (1e16 swallows small terms).
double partial(int t, int row) { return (t % 3 == 0 ? 1e16 : 1.0 + t * 1e-3) * (row + 1) * (t % 2 ? -1 : 1); }

TEST(MpiReducer, TileSumsMatchOneRankBitwise) {
  const int tiles = 23;
  std::vector<int> all(tiles);
  for (int t = 0; t < tiles; ++t) all[t] = t;
  std::vector<double> everything(2 * tiles);
  for (int r = 0; r < 2; ++r)
    for (int t = 0; t < tiles; ++t) everything[r * tiles + t] = partial(t, r);
  double expected[2];
  LocalReducer().sum_tiles(all, everything.data(), 2, expected);

  MpiReducer red(MPI_COMM_WORLD, tiles);
  for (int pattern = 0; pattern < 3; ++pattern) {  // interleaved, blocks, all on rank 1
    std::vector<int> mine;
    for (int t = 0; t < tiles; ++t) {
      const int owner = pattern == 0 ? t % 2 : pattern == 1 ? (t < 9 ? 0 : 1) : 1;
      if (owner == rank()) mine.push_back(t);
    }
    std::vector<double> parts(2 * mine.size());
    for (int r = 0; r < 2; ++r)
      for (size_t k = 0; k < mine.size(); ++k) parts[r * mine.size() + k] = partial(mine[k], r);
    double got[2];
    red.sum_tiles(mine, parts.data(), 2, got);
    EXPECT_EQ(got[0], expected[0]) << "pattern " << pattern;
    EXPECT_EQ(got[1], expected[1]) << "pattern " << pattern;
  }
}

// Every rank's values concatenated in rank order, on every rank: a part of
// none, of a few, and one past the 64 MiB a round moves (two rounds).
TEST(MpiReducer, GatherConcatenatesInRankOrder) {
  MpiReducer red(MPI_COMM_WORLD, 1);
  EXPECT_EQ(red.ranks(), 2);
  const int64_t big = (int64_t(1) << 23) + 3;  // doubles: 64 MiB and 24 bytes
  for (int64_t n1 : {int64_t(0), int64_t(5), big}) {
    const int64_t n = rank() == 0 ? 3 : n1;
    std::vector<double> mine(static_cast<size_t>(n));
    for (int64_t k = 0; k < n; ++k) mine[k] = 1000.0 * rank() + double(k);
    std::vector<int64_t> counts, bytes;
    red.counts(n, counts);
    ASSERT_EQ(counts, (std::vector<int64_t>{3, n1}));
    std::vector<double> all(static_cast<size_t>(3 + n1), -1.0);
    gather_all(red, mine.data(), counts, all.data(), bytes);
    for (int64_t k = 0; k < 3 + n1; ++k)
      ASSERT_EQ(all[k], k < 3 ? double(k) : 1000.0 + double(k - 3)) << "value " << k << " of " << 3 + n1;
  }
}

TEST(MpiReducer, StateChecksumIndependentOfOwnership) {
  Scene s = flat_scene(13, 11, 0.2, 0.2);
  s.cloth.tile = 4;
  Simulation w(s, test_fabric());
  for (size_t k = 0; k < w.cloth.z.size(); ++k) w.cloth.z[k] += 1e-3 * double(k % 17);
  std::vector<int> all, mine;
  for (int t = 0; t < w.tiling.count(); ++t) {
    all.push_back(t);
    if (t % 2 == rank()) mine.push_back(t);
  }
  const std::string one = state_checksum(w.cloth, w.tiling, all, w.red()).hex();
  MpiReducer red(MPI_COMM_WORLD, w.tiling.count());
  EXPECT_EQ(state_checksum(w.cloth, w.tiling, mine, red).hex(), one);
  EXPECT_EQ(red.max(double(rank())), 1.0);
  EXPECT_EQ(red.sum_i64(rank() + 1), 3);
}

}  // namespace
}  // namespace drape::test
