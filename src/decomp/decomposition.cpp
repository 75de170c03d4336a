#include "decomp/decomposition.hpp"

namespace drape {

Decomposition decompose(const Cloth& cloth, const Tiling& tiling, MPI_Comm comm) {
  int rank = 0, ranks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  Decomposition d;
  d.partition = partition_tiles(tiling, tile_work(cloth, tiling), comm);
  d.owned = d.partition.tiles_of(rank);
  if (ranks == 1) {
    d.reducer = std::make_unique<LocalReducer>();
    return d;
  }
  d.halo = std::make_unique<HaloExchange>(tiling, d.partition.owner, comm);
  auto mpi = std::make_unique<MpiReducer>(comm, tiling.count());
  d.mpi_reducer = mpi.get();
  d.reducer = std::move(mpi);
  return d;
}

}  // namespace drape
