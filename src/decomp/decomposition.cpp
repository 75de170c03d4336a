#include "decomp/decomposition.hpp"

#include <algorithm>

namespace drape {

GhostWidths ghost_widths(bool amrc, int max_level) {
  if (!amrc) return {};
  const int reach = 1 << max_level;
  return {4 * reach, 2 * reach};
}

Decomposition decompose(const Cloth& cloth, const Tiling& tiling, MPI_Comm comm, GhostWidths gw,
                        const std::vector<int>* counted) {
  int rank = 0, ranks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  Decomposition d;
  const std::vector<int64_t> work = counted ? tile_work(cloth, tiling, *counted, comm) : tile_work(cloth, tiling);
  d.partition = partition_tiles(tiling, work, comm);
  d.owned = d.partition.tiles_of(rank);
  if (ranks == 1) {
    d.reducer = std::make_unique<LocalReducer>();
    return d;
  }
  d.halo = std::make_unique<HaloExchange>(tiling, d.partition.owner, comm, gw.width, gw.ring);
  auto mpi = std::make_unique<MpiReducer>(comm, tiling.count());
  d.mpi_reducer = mpi.get();
  d.reducer = std::move(mpi);
  return d;
}

Decomposition decompose_in_slots(const Cloth& cloth, const Tiling& tiling, MPI_Comm comm,
                                 const std::function<GhostWidths(const std::vector<int64_t>& held)>& make) {
  int rank = 0, ranks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  const std::vector<int> share = even_share(tiling, rank, ranks);
  const GhostWidths gw = make(with_tiles({}, tiling, share));
  Decomposition d = decompose(cloth, tiling, comm, gw, &share);  // refuses more ranks than tiles
  make(own_particles(tiling, d));
  return d;
}

std::vector<int> even_share(const Tiling& tiling, int rank, int ranks) {
  const int64_t count = tiling.count();
  std::vector<int> tiles;
  for (int64_t t = count * rank / ranks; t < count * (rank + 1) / ranks; ++t) tiles.push_back(int(t));
  return tiles;
}

std::vector<int64_t> own_particles(const Tiling& tiling, const Decomposition& d) {
  return with_tiles(d.halo ? d.halo->ghost_ids() : std::vector<int64_t>{}, tiling, d.owned);
}

void hold_own_particles(Cloth& c, const Tiling& tiling, const Decomposition& d) {
  if (d.halo) hold_with_tiles(c, d.halo->ghost_ids(), tiling, d.owned);
}

void set_ghost_widths(Decomposition& d, Cloth& c, const Tiling& tiling, GhostWidths gw) {
  if (!d.halo) return;
  d.halo->replan(d.partition.owner, gw.width, gw.ring);
  hold_own_particles(c, tiling, d);
}

DecompStats decomp_stats(const Decomposition& d, const Tiling& tl, MPI_Comm comm) {
  DecompStats s;
  s.tiles = tl.count();
  s.tile = tl.t;
  s.imbalance = d.partition.imbalance;
  s.edge_cut = d.partition.edge_cut;
  int64_t mine[2] = {d.halo ? d.halo->ghosts() : 0, d.halo ? d.halo->bytes : 0}, all[2];
  MPI_Allreduce(mine, all, 2, MPI_INT64_T, MPI_SUM, comm);
  s.ghosts = all[0];
  s.halo_bytes = all[1];
  s.exchanges = d.halo ? d.halo->exchanges : 0;
  s.ghost_width = d.halo ? d.halo->width() : 0;
  s.ring_width = d.halo ? d.halo->ring_width() : 0;
  double secs[2] = {d.halo_seconds(), d.reduction_seconds()}, most[2];
  MPI_Allreduce(secs, most, 2, MPI_DOUBLE, MPI_MAX, comm);
  s.halo_seconds = most[0];
  s.reduction_seconds = most[1];
  return s;
}

}  // namespace drape
