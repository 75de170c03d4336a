#pragma once
// The tile graph partitioned with METIS (docs/design.md §3): one vertex per tile,
// weighted by its work (free particles and active elements); one edge
// between tiles that exchange ghosts (the 8 neighbours), weighted by the
// ghost volume between them; one part per rank.
#include <mpi.h>

#include <cstdint>
#include <vector>

#include "mesh/tiles.hpp"
#include "mesh/cloth.hpp"

namespace drape {

struct Partition {
  std::vector<int> owner;     // rank per tile
  std::vector<int64_t> work;  // per rank
  int64_t edge_cut = 0;       // ghost volume between tiles of different ranks
  double imbalance = 1.0;     // max / mean work per rank

  std::vector<int> tiles_of(int rank) const;  // ascending
};

// Work per tile: free particles plus active edges, triples and shear corners.
// Of every tile: c must hold every particle (one rank, or before decomposing).
std::vector<int64_t> tile_work(const Cloth& c, const Tiling& tiling);
// Of every tile on several ranks, each counting the tiles `owned` it holds
// (the element switches are held in slots); collective.
std::vector<int64_t> tile_work(const Cloth& c, const Tiling& tiling, const std::vector<int>& owned, MPI_Comm comm);

// The figures (work per rank, imbalance, edge cut) of a given owner map.
Partition partition_with(const Tiling& tiling, const std::vector<int>& owner, const std::vector<int64_t>& work,
                         int parts);

// METIS_PartGraphKway into `parts` parts (all tiles to rank 0 for one part);
// a part METIS leaves without a tile takes the lightest tile of the part
// with the most. Throws std::runtime_error when METIS fails.
Partition partition_graph(const Tiling& tiling, const std::vector<int64_t>& work, int parts);

// Collective: rank 0 partitions, every rank gets the same result. More ranks
// than tiles is an InputError; a METIS failure a CollectiveError, on every rank.
Partition partition_tiles(const Tiling& tiling, const std::vector<int64_t>& work, MPI_Comm comm);

}  // namespace drape
