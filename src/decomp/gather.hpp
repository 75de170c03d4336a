#pragma once
// Whole arrays on rank 0, for what only rank 0 does with the whole cloth
// (the picture): every rank sends its tiles' values, tile by tile.
#include <mpi.h>

#include <vector>

#include "mesh/tiles.hpp"

namespace drape {

// `data` holds `per` values per particle in global order; on return rank 0's
// copy is complete (other ranks' are unchanged). Collective.
void gather_on_root(double* data, int per, const Tiling& tiling, const std::vector<int>& owner,
                    MPI_Comm comm);

}  // namespace drape
