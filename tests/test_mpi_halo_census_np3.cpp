// Three ranks: the scale model's halo counts (halo_census, all ranks from
// one process) against what a real HaloExchange plans and sends on each
// rank, for several owner maps of an awkward grid.
#include <gtest/gtest.h>
#include <mpi.h>

#include <vector>

#include "decomp/collective.hpp"
#include "decomp/halo_census.hpp"
#include "decomp/halo_exchange.hpp"
#include "decomp/partition.hpp"

namespace drape::test {
namespace {

// Tiles clipped at both far borders.
const Tiling kTiling(41, 37, 6);

void expect_census_matches_exchange(const std::vector<int>& owner, int width) {
  const int me = rank_of(MPI_COMM_WORLD), ranks = size_of(MPI_COMM_WORLD);
  const HaloCensus census = halo_census(kTiling, owner, ranks, width);
  HaloExchange halo(kTiling, owner, MPI_COMM_WORLD, width, 1);
  std::vector<double> a(size_t(kTiling.ni) * kTiling.nj, 1.0);
  halo.exchange_particles(a.data(), 1);  // one double a particle sent
  EXPECT_EQ(census.received[me], halo.ghosts());
  EXPECT_EQ(census.neighbours[me], halo.neighbours());
  EXPECT_EQ(census.sent[me] * int64_t(sizeof(double)), halo.bytes);
}

TEST(HaloCensus, MatchesTheExchangeOnMetisParts) {
  const std::vector<int64_t> work(kTiling.count(), 10);
  const Partition p = partition_graph(kTiling, work, size_of(MPI_COMM_WORLD));
  expect_census_matches_exchange(p.owner, 2);
}

TEST(HaloCensus, MatchesTheExchangeOnScatteredTiles) {
  std::vector<int> owner(kTiling.count());
  for (int t = 0; t < kTiling.count(); ++t) owner[t] = (t * 7 + t / 3) % size_of(MPI_COMM_WORLD);
  expect_census_matches_exchange(owner, 2);
  expect_census_matches_exchange(owner, 4);  // AMRC's wider ghosts
}

TEST(HaloCensus, StripesMeetOnlyTheirNeighbours) {
  std::vector<int> owner(kTiling.count());
  for (int t = 0; t < kTiling.count(); ++t) owner[t] = std::min(2, (t / kTiling.ntj) * 3 / kTiling.nti);
  const HaloCensus c = halo_census(kTiling, owner, 3, 2);
  EXPECT_EQ(c.neighbours, (std::vector<int>{1, 2, 1}));
  // Two rows of the full width on each side of each cut.
  EXPECT_EQ(c.sent[0], 2 * kTiling.nj);
  EXPECT_EQ(c.sent[1], 4 * kTiling.nj);
  expect_census_matches_exchange(owner, 2);
}

}  // namespace
}  // namespace drape::test
