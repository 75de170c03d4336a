// Three ranks: the METIS partition of the tiles and the halo exchange. As in
// GROMACS's halo tests, every value a rank sends encodes its owner rank, the
// particle's global id and the component, so a ghost that arrives from the
// wrong rank, for the wrong particle or into the wrong slot shows which.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <limits>
#include <map>

#include "decomp/collective.hpp"
#include "decomp/decomposition.hpp"
#include "base/error.hpp"

namespace drape::test {
namespace {

int rank() { return rank_of(MPI_COMM_WORLD); }

// An awkward grid: tiles clipped at both far borders.
const Tiling kTiling(23, 19, 4);

std::vector<int64_t> uniform_work() { return std::vector<int64_t>(kTiling.count(), 10); }

// rank * 1e7 + particle * 10 + component: exact in a double.
double code(int owner, int64_t p, int comp) { return owner * 1e7 + double(p) * 10 + comp; }

// Chebyshev distance from particle p to the nearest particle this rank owns.
int distance_to_mine(const std::vector<int>& owner, int64_t p) {
  const int i = int(p / kTiling.nj), j = int(p % kTiling.nj);
  int best = 1 << 20;
  for (int a = 0; a < kTiling.ni; ++a)
    for (int b = 0; b < kTiling.nj; ++b)
      if (owner[kTiling.tile_of(a, b)] == rank())
        best = std::min(best, std::max(std::abs(a - i), std::abs(b - j)));
  return best;
}

TEST(Partition, EveryTileOwnedTheSameOnEveryRank) {
  const Partition p = partition_tiles(kTiling, uniform_work(), MPI_COMM_WORLD);
  ASSERT_EQ(int(p.owner.size()), kTiling.count());
  std::vector<int> root = p.owner;
  MPI_Bcast(root.data(), int(root.size()), MPI_INT, 0, MPI_COMM_WORLD);
  EXPECT_EQ(p.owner, root);
  int64_t total = 0;
  for (int r = 0; r < 3; ++r) {
    EXPECT_FALSE(p.tiles_of(r).empty()) << "rank " << r;
    total += p.work[r];
  }
  EXPECT_EQ(total, 10 * kTiling.count());
  const int64_t most = *std::max_element(p.work.begin(), p.work.end());
  EXPECT_DOUBLE_EQ(p.imbalance, double(most) * 3 / double(total));
  EXPECT_LE(p.imbalance, 1.2);
  EXPECT_GT(p.edge_cut, 0);
}

TEST(Partition, MoreRanksThanTilesIsRefusedOnEveryRank) {
  const Tiling two(8, 4, 4);  // 2 tiles, 3 ranks
  EXPECT_THROW(partition_tiles(two, std::vector<int64_t>(2, 1), MPI_COMM_WORLD), InputError);
  // Every rank threw and is here: no rank waits in a collective.
  MPI_Barrier(MPI_COMM_WORLD);
}

// METIS leaves parts empty when there are few tiles per part and the work
// is uneven (four tiles of work 100, 1, 1, 1 in three parts: two empty);
// every rank must still get a tile, at start-up and at a rebalance.
TEST(Partition, FewUnevenTilesLeaveNoRankEmpty) {
  const Tiling four(8, 8, 4);
  const Partition p = partition_tiles(four, {100, 1, 1, 1}, MPI_COMM_WORLD);
  for (int r = 0; r < 3; ++r) EXPECT_FALSE(p.tiles_of(r).empty()) << "rank " << r;
  // The same on more tile counts and parts, on rank 0's METIS alone.
  for (int side = 1; side <= 6; ++side)
    for (int parts = 2; parts <= 9; ++parts)
      for (int stride : {2, 3, 7}) {
        const Tiling tl(4 * side, 4 * side, 4);
        if (parts > tl.count()) continue;
        std::vector<int64_t> work(tl.count(), 1);
        for (int t = 0; t < tl.count(); t += stride) work[t] = 100;
        const Partition q = partition_graph(tl, work, parts);
        for (int r = 0; r < parts; ++r)
          EXPECT_GT(q.work[r], 0) << side << " x " << side << " tiles, " << parts << " parts, stride " << stride;
      }
}

TEST(Halo, EveryGhostCarriesItsOwnerAndId) {
  const Partition part = partition_tiles(kTiling, uniform_work(), MPI_COMM_WORLD);
  const HaloExchange halo(kTiling, part.owner, MPI_COMM_WORLD);
  const int64_t n = int64_t(kTiling.ni) * kTiling.nj;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> z(8 * n, nan);
  const int64_t off[4] = {0, 3 * n, 5 * n, 7 * n};
  const int per[4] = {3, 2, 2, 1};
  auto owner_of = [&](int64_t p) { return part.owner[kTiling.tile_of(p)]; };
  // Component numbering across z's blocks: 0-2 positions, 3-4 tension,
  // 5-6 moment, 7 shear.
  auto each_entry = [&](int64_t p, auto&& f) {
    int comp = 0;
    for (int b = 0; b < 4; ++b)
      for (int c = 0; c < per[b]; ++c) f(off[b] + per[b] * p + c, comp++, b);
  };
  for (int64_t p = 0; p < n; ++p)
    if (owner_of(p) == rank()) each_entry(p, [&](int64_t k, int comp, int) { z[k] = code(rank(), p, comp); });

  // Positions only first: forces of ghosts stay untouched.
  halo.exchange(z.data(), Halo::kPositions);
  int64_t ghosts = 0, ring = 0;
  for (int64_t p = 0; p < n; ++p) {
    const int o = owner_of(p);
    if (o == rank()) continue;
    const int dist = distance_to_mine(part.owner, p);
    ghosts += dist <= 2;
    ring += dist <= 1;
    each_entry(p, [&](int64_t k, int comp, int block) {
      if (dist <= 2 && block == 0)
        EXPECT_EQ(z[k], code(o, p, comp)) << "ghost " << p << " comp " << comp << " on rank " << rank();
      else
        EXPECT_TRUE(std::isnan(z[k])) << "particle " << p << " comp " << comp << " written on rank " << rank();
    });
  }
  EXPECT_EQ(halo.ghosts(), ghosts);
  EXPECT_EQ(int64_t(halo.ring().size()), ring);
  for (int64_t p : halo.ring()) EXPECT_EQ(distance_to_mine(part.owner, p), 1) << p;

  halo.exchange(z.data(), Halo::kAll);
  for (int64_t p = 0; p < n; ++p) {
    const int o = owner_of(p);
    if (o == rank() || distance_to_mine(part.owner, p) > 2) continue;
    each_entry(p, [&](int64_t k, int comp, int) {
      EXPECT_EQ(z[k], code(o, p, comp)) << "ghost " << p << " comp " << comp << " on rank " << rank();
    });
  }

  // A per-particle array (the residuals): 3 values per particle.
  std::vector<double> rho(3 * n, nan);
  for (int64_t p = 0; p < n; ++p)
    if (owner_of(p) == rank())
      for (int c = 0; c < 3; ++c) rho[3 * p + c] = code(rank(), p, c);
  halo.exchange_particles(rho.data(), 3);
  for (int64_t p = 0; p < n; ++p)
    if (owner_of(p) != rank() && distance_to_mine(part.owner, p) <= 2) {
      for (int c = 0; c < 3; ++c) EXPECT_EQ(rho[3 * p + c], code(owner_of(p), p, c)) << p;
    }
}


// The same exchange for a vector in a rank's own numbering (Halo::plan,
// exchange_at): the own particles numbered backwards, the received ones
// after them in the plan's reverse order, so that no index equals a grid
// id's. Every fifth received particle has no index (dropped), every
// seventh particle none on its owner (sent as 0).
TEST(Halo, OwnNumberingCarriesOwnerAndId) {
  const Partition part = partition_tiles(kTiling, uniform_work(), MPI_COMM_WORLD);
  const HaloExchange halo(kTiling, part.owner, MPI_COMM_WORLD);
  const int64_t n = int64_t(kTiling.ni) * kTiling.nj;
  auto owner_of = [&](int64_t p) { return part.owner[kTiling.tile_of(p)]; };
  std::vector<int64_t> sent, received;
  halo.plan([&](int64_t p, bool send) { (send ? sent : received).push_back(p); });
  ASSERT_EQ(int64_t(received.size()), halo.ghosts());
  for (int64_t p : sent) EXPECT_EQ(owner_of(p), rank()) << "sends " << p;
  for (int64_t p : received) EXPECT_NE(owner_of(p), rank()) << "receives " << p;
  std::map<int64_t, int32_t> index;  // grid id -> own numbering
  for (int64_t p = n - 1; p >= 0; --p)
    if (owner_of(p) == rank() && p % 7 != 0) index[p] = int32_t(index.size());
  for (size_t k = received.size(); k-- > 0;)
    if (k % 5 != 0) {
      ASSERT_EQ(index.count(received[k]), 0u) << received[k] << " received twice";
      index[received[k]] = int32_t(index.size());
    }
  auto at = [&](int64_t p) { return index.count(p) ? index.at(p) : int32_t(-1); };
  std::vector<int32_t> send_at, recv_at;
  for (int64_t p : sent) send_at.push_back(at(p));
  for (int64_t p : received) recv_at.push_back(at(p));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> a(3 * index.size(), nan);
  for (const auto& [p, l] : index)
    if (owner_of(p) == rank())
      for (int c = 0; c < 3; ++c) a[3 * size_t(l) + c] = code(rank(), p, c);
  halo.exchange_at(a.data(), send_at.data(), recv_at.data());
  for (const auto& [p, l] : index)
    for (int c = 0; c < 3; ++c) {
      const double want = p % 7 == 0 ? 0.0 : code(owner_of(p), p, c);
      EXPECT_EQ(a[3 * size_t(l) + c], want) << "particle " << p << " comp " << c << " on rank " << rank();
    }
}

}  // namespace
}  // namespace drape::test
