// Three ranks: tiles migrate to a new partition with every value of their
// particles, bit for bit, and back again; after a migration the halo
// exchange of the new partition delivers every ghost from its new owner.
// Values encode the rank that first owned them, the particle and the field.
// A rebalance moves tiles only when the loads drift apart, then evens them.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "decomp/collective.hpp"
#include "decomp/halo_exchange.hpp"
#include "decomp/migrate.hpp"
#include "decomp/partition.hpp"
#include "decomp/rebalance.hpp"
#include "solver/model.hpp"
#include "support/scenes.hpp"

namespace drape::test {
namespace {

int rank() { return rank_of(MPI_COMM_WORLD); }

double code(int owner, int64_t p, int field) { return owner * 1e7 + double(p) * 20 + field; }

// Every migrated value of particle p, in a fixed order (16 fields).
std::vector<double*> fields(Cloth& c, int64_t p) {
  const int64_t n = c.grid.n();
  std::vector<double*> f;
  for (int k = 0; k < 3; ++k) f.push_back(&c.z[3 * p + k]);
  for (int k = 0; k < 2; ++k) f.push_back(&c.z[3 * n + 2 * p + k]);
  for (int k = 0; k < 2; ++k) f.push_back(&c.z[5 * n + 2 * p + k]);
  f.push_back(&c.z[7 * n + p]);
  for (int k = 0; k < 3; ++k) f.push_back(&c.x1[3 * p + k]);
  for (int k = 0; k < 3; ++k) f.push_back(&c.x2[3 * p + k]);
  return f;
}

struct Shares {
  Cloth cloth;
  Tiling tiling{23, 19, 4};
  std::vector<int> first, second;  // two partitions
  std::vector<int64_t> work;
};

Shares shares() {
  Shares s;
  Scene scene = flat_scene(23, 19, 0.22, 0.18);
  s.cloth = make_cloth(scene, test_fabric());
  s.work.assign(s.tiling.count(), 1);
  s.first = partition_tiles(s.tiling, s.work, MPI_COMM_WORLD).owner;
  // A very different split: tiles dealt round-robin, then relabelled.
  std::vector<int> dealt(s.tiling.count());
  for (int t = 0; t < s.tiling.count(); ++t) dealt[t] = (t * 7 + 1) % 3;
  s.second = relabel_to_overlap(s.first, dealt, s.work, 3);
  // Encode: rank r's tiles hold r's codes, flags and levels too; NaN elsewhere.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int64_t p = 0; p < s.cloth.grid.n(); ++p) {
    const bool mine = s.first[s.tiling.tile_of(p)] == rank();
    const std::vector<double*> f = fields(s.cloth, p);
    for (size_t k = 0; k < f.size(); ++k) *f[k] = mine ? code(rank(), p, int(k)) : nan;
    s.cloth.flags[p] = mine ? uint8_t(1 + (p + rank()) % 5) : 0;
    s.cloth.level[p] = mine ? uint8_t((p * 3 + rank()) % 7) : 0;
  }
  return s;
}

TEST(Migrate, RelabelKeepsMoreTilesInPlace) {
  Shares s = shares();
  std::vector<int> dealt(s.tiling.count());
  for (int t = 0; t < s.tiling.count(); ++t) dealt[t] = (t * 7 + 1) % 3;
  int raw = 0, relabelled = 0;
  for (int t = 0; t < s.tiling.count(); ++t) {
    raw += dealt[t] != s.first[t];
    relabelled += s.second[t] != s.first[t];
  }
  EXPECT_LE(relabelled, raw);
  // Still a partition into the same three part sizes.
  std::vector<int> a(3, 0), b(3, 0);
  for (int t = 0; t < s.tiling.count(); ++t) ++a[dealt[t]], ++b[s.second[t]];
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  EXPECT_EQ(a, b);
}

TEST(Migrate, TilesArriveWithEveryValueAndGoBackBitForBit) {
  Shares s = shares();
  const Cloth before = s.cloth;
  const MigrationStats st = migrate_tiles(s.cloth, s.tiling, s.first, s.second, MPI_COMM_WORLD);
  int moved = 0;
  for (int t = 0; t < s.tiling.count(); ++t) moved += s.first[t] != s.second[t];
  EXPECT_EQ(st.tiles_moved, moved);
  EXPECT_GT(moved, 0);
  for (int64_t p = 0; p < s.cloth.grid.n(); ++p) {
    const int t = s.tiling.tile_of(p);
    if (s.second[t] != rank()) continue;
    const int from = s.first[t];
    const std::vector<double*> f = fields(s.cloth, p);
    for (size_t k = 0; k < f.size(); ++k)
      ASSERT_EQ(*f[k], code(from, p, int(k))) << "particle " << p << " field " << k << " on rank " << rank();
    EXPECT_EQ(s.cloth.flags[p], uint8_t(1 + (p + from) % 5));
    EXPECT_EQ(s.cloth.level[p], uint8_t((p * 3 + from) % 7));
  }
  // The new partition's halo: every ghost from its new owner, holding the
  // values of the rank that first owned it.
  const HaloExchange halo(s.tiling, s.second, MPI_COMM_WORLD);
  halo.exchange(s.cloth.z.data(), Halo::kAll);
  halo.exchange_particles(s.cloth.x1.data(), 3);
  for (int64_t p : halo.ring()) {
    const int from = s.first[s.tiling.tile_of(p)];
    const std::vector<double*> f = fields(s.cloth, p);
    for (size_t k = 0; k < 11; ++k)  // z (8 fields) and x1 (3)
      EXPECT_EQ(*f[k], code(from, p, int(k))) << "ghost " << p << " field " << k << " on rank " << rank();
  }
  // And back: the original owners' values, bit for bit.
  migrate_tiles(s.cloth, s.tiling, s.second, s.first, MPI_COMM_WORLD);
  Cloth& c = s.cloth;
  for (int64_t p = 0; p < c.grid.n(); ++p) {
    if (s.first[s.tiling.tile_of(p)] != rank()) continue;
    Cloth& b = const_cast<Cloth&>(before);
    const std::vector<double*> f = fields(c, p), g = fields(b, p);
    for (size_t k = 0; k < f.size(); ++k)
      ASSERT_EQ(std::memcmp(f[k], g[k], sizeof(double)), 0) << "particle " << p << " field " << k;
    EXPECT_EQ(c.flags[p], before.flags[p]);
    EXPECT_EQ(c.level[p], before.level[p]);
  }
}

// After AMRC: a balanced partition stays put; when one rank's tiles lose
// their work (a coarse region), the tiles are partitioned again, fewer than
// all move, the loads even out, and the new halo serves every ghost from its
// new owner.
TEST(Rebalance, OnlyWhenImbalancedThenEvensTheLoad) {
  Scene scene = flat_scene(23, 19, 0.22, 0.18);
  Cloth c = make_cloth(scene, test_fabric());
  const Tiling tl(23, 19, 4);
  Decomposition d = decompose(c, tl, MPI_COMM_WORLD);
  const std::vector<int> first = d.partition.owner;
  Rebalance rb;
  EXPECT_FALSE(rebalance(d, c, tl, 10.0, MPI_COMM_WORLD, rb)) << "imbalance " << rb.imbalance_before;
  EXPECT_EQ(d.partition.owner, first);
  // Rank 0's tiles go flat: no free particles, no elements (every rank
  // does the same to its copy of the flags, as AMRC's replicated tree does).
  for (int64_t p = 0; p < c.grid.n(); ++p) {
    if (first[tl.tile_of(p)] != 0) continue;
    c.flags[p] = 0;
    for (int k = 0; k < 2; ++k) c.edge_on[2 * p + k] = c.triple_on[2 * p + k] = 0;
    c.shear_on[p] = 0;
  }
  for (int64_t p = 0; p < c.grid.n(); ++p)  // positions encode the first owner
    for (int k = 0; k < 3; ++k) c.z[3 * p + k] = first[tl.tile_of(p)] == rank() ? code(rank(), p, k) : -1;
  ASSERT_TRUE(rebalance(d, c, tl, 1.05, MPI_COMM_WORLD, rb));
  EXPECT_GT(rb.imbalance_before, 1.3);
  EXPECT_LT(rb.imbalance_after, rb.imbalance_before);
  EXPECT_LE(rb.imbalance_after, 1.2);
  EXPECT_GT(rb.tiles_moved, 0);
  EXPECT_LT(rb.tiles_moved, tl.count());
  EXPECT_EQ(d.owned, d.partition.tiles_of(rank()));
  EXPECT_DOUBLE_EQ(d.partition.imbalance, rb.imbalance_after);
  d.halo->exchange(c.z.data(), Halo::kPositions);
  for (int t : d.owned) {  // own tiles, moved or not
    const TileRange r = tl.range(t);
    for (int i = r.i0; i < r.i1; ++i)
      for (int j = r.j0; j < r.j1; ++j) {
        const int64_t p = c.grid.id(i, j);
        ASSERT_EQ(c.z[3 * p], code(first[t], p, 0)) << "particle " << p << " on rank " << rank();
      }
  }
  for (int64_t p : d.halo->ring())
    EXPECT_EQ(c.z[3 * p + 1], code(first[tl.tile_of(p)], p, 1)) << "ghost " << p << " on rank " << rank();
}

// The element switches are held in slots: a rank counts the work of the
// tiles it owns and the ranks sum them into the whole cloth's work, which
// its own held cloth alone no longer gives.
TEST(Rebalance, TileWorkSummedOverOwnersIsTheWholeCloths) {
  Scene scene = flat_scene(23, 19, 0.22, 0.18);
  const Cloth whole = make_cloth(scene, test_fabric());
  Cloth c = whole;
  const Tiling tl(23, 19, 4);
  Decomposition d = decompose(c, tl, MPI_COMM_WORLD);
  hold_own_particles(c, tl, d);
  EXPECT_EQ(tile_work(c, tl, d.owned, MPI_COMM_WORLD), tile_work(whole, tl));
  EXPECT_NE(tile_work(c, tl), tile_work(whole, tl)) << "switches of tiles not held: still the grid's?";
}

}  // namespace
}  // namespace drape::test
