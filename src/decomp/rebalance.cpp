#include "decomp/rebalance.hpp"

#include <algorithm>

#include "decomp/migrate.hpp"

namespace drape {

std::vector<int> diffuse_tiles(const Tiling& tl, std::vector<int> owner, const std::vector<int64_t>& work,
                               int ranks, double target) {
  std::vector<int64_t> load(ranks, 0);
  int64_t total = 0;
  for (int t = 0; t < tl.count(); ++t) {
    load[owner[t]] += work[t];
    total += work[t];
  }
  for (int moves = 0; moves < tl.count(); ++moves) {
    int r = 0;
    for (int k = 1; k < ranks; ++k)
      if (load[k] > load[r]) r = k;
    if (double(load[r]) * ranks <= target * double(total)) break;
    int64_t best = load[r];
    int bt = -1, bs = -1;
    for (int t = 0; t < tl.count(); ++t) {
      if (owner[t] != r) continue;
      const int ti = t / tl.ntj, tj = t % tl.ntj;
      for (int di = -1; di <= 1; ++di)
        for (int dj = -1; dj <= 1; ++dj) {
          const int ui = ti + di, uj = tj + dj;
          if (ui < 0 || uj < 0 || ui >= tl.nti || uj >= tl.ntj) continue;
          const int s = owner[ui * tl.ntj + uj];
          if (s == r) continue;
          const int64_t after = std::max(load[r] - work[t], load[s] + work[t]);
          if (after < best) {
            best = after;
            bt = t;
            bs = s;
          }
        }
    }
    if (bt < 0) break;  // no single move lowers the largest load
    load[r] -= work[bt];
    load[bs] += work[bt];
    owner[bt] = bs;
  }
  return owner;
}

bool rebalance(Decomposition& d, Cloth& c, const Tiling& tl, double threshold, MPI_Comm comm,
               Rebalance& out) {
  int rank = 0, ranks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  const std::vector<int64_t> work = tile_work(c, tl, d.owned, comm);
  const Partition now = partition_with(tl, d.partition.owner, work, ranks);
  out.imbalance_before = out.imbalance_after = now.imbalance;
  out.edge_cut = now.edge_cut;
  d.partition = now;
  if (ranks == 1 || now.imbalance <= threshold) return false;
  // A few boundary tiles moved usually suffice; METIS's fresh parts, even
  // renamed to overlap the old ones, can move half the cloth.
  std::vector<int> owner = diffuse_tiles(tl, now.owner, work, ranks, threshold);
  double best = partition_with(tl, owner, work, ranks).imbalance;
  out.method = "diffusion";
  if (best > threshold) {  // METIS only if it beats what diffusion reached
    const Partition fresh = partition_tiles(tl, work, comm);
    if (fresh.imbalance < best) {
      owner = relabel_to_overlap(now.owner, fresh.owner, work, ranks);
      best = fresh.imbalance;
      out.method = "metis";
    }
  }
  if (!(best < now.imbalance)) return false;  // nothing does better with these tiles
  const MigrationStats m = migrate_tiles(c, tl, now.owner, owner, comm);
  d.partition = partition_with(tl, owner, work, ranks);
  d.owned = d.partition.tiles_of(rank);
  if (d.halo) d.halo->replan(owner);
  hold_own_particles(c, tl, d);  // the new tiles' and ghosts' history and forces, no more
  out.imbalance_after = d.partition.imbalance;
  out.edge_cut = d.partition.edge_cut;
  out.tiles_moved = m.tiles_moved;
  out.bytes_moved = m.bytes;
  return true;
}

}  // namespace drape
