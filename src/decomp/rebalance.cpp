#include "decomp/rebalance.hpp"

#include "decomp/migrate.hpp"

namespace drape {

bool rebalance(Decomposition& d, Cloth& c, const Tiling& tl, double threshold, MPI_Comm comm,
               Rebalance& out) {
  int rank = 0, ranks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  const std::vector<int64_t> work = tile_work(c, tl);  // flags are the same on every rank
  const Partition now = partition_with(tl, d.partition.owner, work, ranks);
  out.imbalance_before = out.imbalance_after = now.imbalance;
  out.edge_cut = now.edge_cut;
  d.partition = now;
  if (ranks == 1 || now.imbalance <= threshold) return false;
  const Partition fresh = partition_tiles(tl, work, comm);
  if (fresh.imbalance >= now.imbalance) return false;  // METIS cannot do better with these tiles
  const std::vector<int> owner = relabel_to_overlap(now.owner, fresh.owner, work, ranks);
  const MigrationStats m = migrate_tiles(c, tl, now.owner, owner, comm);
  d.partition = partition_with(tl, owner, work, ranks);
  d.owned = d.partition.tiles_of(rank);
  if (d.halo) d.halo->replan(owner);
  out.imbalance_after = d.partition.imbalance;
  out.edge_cut = d.partition.edge_cut;
  out.tiles_moved = m.tiles_moved;
  out.bytes_moved = m.bytes;
  return true;
}

}  // namespace drape
