#include "decomp/partition.hpp"

#include <metis.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include "base/error.hpp"

namespace drape {

std::vector<int> Partition::tiles_of(int rank) const {
  std::vector<int> out;
  for (int t = 0; t < int(owner.size()); ++t)
    if (owner[t] == rank) out.push_back(t);
  return out;
}

namespace {
int64_t work_of(const Cloth& c, const Tiling& tiling, int t) {
  const TileRange r = tiling.range(t);
  int64_t w = 0;
  for (int i = r.i0; i < r.i1; ++i)
    for (int j = r.j0; j < r.j1; ++j) {
      const int64_t p = c.grid.id(i, j);
      w += c.free(p) + c.edge_on_at(2 * p) + c.edge_on_at(2 * p + 1) + c.triple_on_at(2 * p) +
           c.triple_on_at(2 * p + 1) + c.shear_on_at(p);
    }
  return std::max<int64_t>(1, w);  // METIS wants positive weights
}
}  // namespace

std::vector<int64_t> tile_work(const Cloth& c, const Tiling& tiling) {
  std::vector<int64_t> work(tiling.count(), 0);
  for (int t = 0; t < tiling.count(); ++t) work[t] = work_of(c, tiling, t);
  return work;
}

std::vector<int64_t> tile_work(const Cloth& c, const Tiling& tiling, const std::vector<int>& owned, MPI_Comm comm) {
  std::vector<int64_t> work(tiling.count(), 0);
  for (int t : owned) work[t] = work_of(c, tiling, t);
  MPI_Allreduce(MPI_IN_PLACE, work.data(), int(work.size()), MPI_INT64_T, MPI_SUM, comm);
  return work;
}

namespace {

// The ghost volume between two tiles: both sides' particles within two of
// the shared side (or corner).
idx_t ghost_volume(const Tiling& tl, int a, int b) {
  const TileRange ra = tl.range(a), rb = tl.range(b);
  const int si = std::min(ra.i1, rb.i1) - std::max(ra.i0, rb.i0);
  const int sj = std::min(ra.j1, rb.j1) - std::max(ra.j0, rb.j0);
  const int shared = std::max(si, sj);  // the side's length (0 on a corner)
  return idx_t(std::max(4, 4 * shared));
}

void fill_stats(const Tiling& tl, const std::vector<int64_t>& work, int parts, Partition& p) {
  p.work.assign(parts, 0);
  for (int t = 0; t < tl.count(); ++t) p.work[p.owner[t]] += work[t];
  int64_t total = 0, most = 0;
  for (int64_t w : p.work) {
    total += w;
    most = std::max(most, w);
  }
  p.imbalance = total > 0 ? double(most) * parts / double(total) : 1.0;
  p.edge_cut = 0;
  for (int t = 0; t < tl.count(); ++t) {
    const int ti = t / tl.ntj, tj = t % tl.ntj;
    for (int di = -1; di <= 1; ++di)
      for (int dj = -1; dj <= 1; ++dj) {
        const int ui = ti + di, uj = tj + dj;
        if ((di == 0 && dj == 0) || ui < 0 || uj < 0 || ui >= tl.nti || uj >= tl.ntj) continue;
        const int u = ui * tl.ntj + uj;
        if (u > t && p.owner[u] != p.owner[t]) p.edge_cut += ghost_volume(tl, t, u);
      }
  }
}

// METIS can leave a part without a tile when there are few tiles per part
// and the work is uneven. Each empty part takes the lightest tile (lowest id
// among equals) of the part holding the most tiles, until none is empty.
void fill_empty_parts(const std::vector<int64_t>& work, int parts, std::vector<int>& owner) {
  std::vector<int> count(parts, 0);
  for (int o : owner) ++count[o];
  for (int r = 0; r < parts; ++r) {
    if (count[r] > 0) continue;
    const int donor = int(std::max_element(count.begin(), count.end()) - count.begin());
    int pick = -1;
    for (int t = 0; t < int(owner.size()); ++t)
      if (owner[t] == donor && (pick < 0 || work[t] < work[pick])) pick = t;
    owner[pick] = r;
    --count[donor];
    ++count[r];
  }
}

}  // namespace

Partition partition_with(const Tiling& tl, const std::vector<int>& owner, const std::vector<int64_t>& work,
                         int parts) {
  Partition p;
  p.owner = owner;
  fill_stats(tl, work, parts, p);
  return p;
}

Partition partition_graph(const Tiling& tl, const std::vector<int64_t>& work, int parts) {
  Partition p;
  const int n = tl.count();
  if (parts < 1 || parts > n)
    throw std::runtime_error("partition: " + std::to_string(parts) + " parts for " + std::to_string(n) + " tiles");
  p.owner.assign(n, 0);
  if (parts > 1) {
    // CSR graph of the tiles and their 8 neighbours.
    std::vector<idx_t> xadj = {0}, adjncy, adjwgt, vwgt(n);
    for (int t = 0; t < n; ++t) {
      vwgt[t] = idx_t(work[t]);
      const int ti = t / tl.ntj, tj = t % tl.ntj;
      for (int di = -1; di <= 1; ++di)
        for (int dj = -1; dj <= 1; ++dj) {
          const int ui = ti + di, uj = tj + dj;
          if ((di == 0 && dj == 0) || ui < 0 || uj < 0 || ui >= tl.nti || uj >= tl.ntj) continue;
          adjncy.push_back(ui * tl.ntj + uj);
          adjwgt.push_back(ghost_volume(tl, t, ui * tl.ntj + uj));
        }
      xadj.push_back(idx_t(adjncy.size()));
    }
    idx_t nv = n, ncon = 1, np = parts, objval = 0;
    idx_t options[METIS_NOPTIONS];
    METIS_SetDefaultOptions(options);
    options[METIS_OPTION_SEED] = 7;      // the same parts on every run
    options[METIS_OPTION_UFACTOR] = 30;  // at most 1.03 x the mean work
    std::vector<idx_t> part(n, 0);
    const int rc = METIS_PartGraphKway(&nv, &ncon, xadj.data(), adjncy.data(), vwgt.data(), nullptr,
                                       adjwgt.data(), &np, nullptr, nullptr, options, &objval,
                                       part.data());
    if (rc != METIS_OK)
      throw std::runtime_error("partition: METIS_PartGraphKway failed (status " + std::to_string(rc) +
                               ") for " + std::to_string(parts) + " parts of " + std::to_string(n) + " tiles");
    for (int t = 0; t < n; ++t) p.owner[t] = int(part[t]);
    fill_empty_parts(work, parts, p.owner);  // 4 tiles of work 100, 1, 1, 1 in 3 parts: two empty
  }
  fill_stats(tl, work, parts, p);
  return p;
}

Partition partition_tiles(const Tiling& tl, const std::vector<int64_t>& work, MPI_Comm comm) {
  int rank = 0, ranks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  if (ranks > tl.count())
    throw InputError("MPI: " + std::to_string(ranks) + " ranks but the cloth has only " +
                     std::to_string(tl.count()) + " tile(s) (cloth.tile = " + std::to_string(tl.t) +
                     "): run at most " + std::to_string(tl.count()) + " ranks or set a smaller cloth.tile");
  Partition p;
  char error[256] = {0};
  if (rank == 0) {
    try {
      p = partition_graph(tl, work, ranks);
    } catch (const std::exception& e) {
      std::snprintf(error, sizeof error, "%s", e.what());
    }
  }
  // Rank 0's verdict and parts reach every rank, so none waits alone.
  MPI_Bcast(error, sizeof error, MPI_CHAR, 0, comm);
  if (error[0]) throw CollectiveError(error);
  p.owner.resize(tl.count());
  MPI_Bcast(p.owner.data(), tl.count(), MPI_INT, 0, comm);
  if (rank != 0) fill_stats(tl, work, ranks, p);
  for (int r = 0; r < ranks; ++r)
    if (p.work[r] == 0) throw CollectiveError("partition: rank " + std::to_string(r) + " got no tile");
  return p;
}

}  // namespace drape
