#pragma once
// Values on rank 0, for what only rank 0 writes: whole arrays, the values
// of listed particles (the picture's samples), or rasters or-ed together
// (the drape test's shadow).
#include <mpi.h>

#include <cstdint>
#include <vector>

#include "mesh/tiles.hpp"

namespace drape {

// `data` holds `per` values per particle in global order; on return rank 0's
// copy is complete (other ranks' are unchanged). Collective.
void gather_on_root(double* data, int per, const Tiling& tiling, const std::vector<int>& owner,
                    MPI_Comm comm);

// The `per` values of each particle of `listed` (ascending, the same on
// every rank) from its tile's owner: on rank 0, per x listed.size() values in
// listed's order; elsewhere empty. Collective.
std::vector<double> gather_listed_on_root(const double* data, int per, const std::vector<int64_t>& listed,
                                          const Tiling& tiling, const std::vector<int>& owner, MPI_Comm comm);

// On rank 0, the bitwise or of every rank's `bytes` (the same length on
// each); the others' are unchanged. Collective.
void or_on_root(std::vector<uint8_t>& bytes, MPI_Comm comm);

}  // namespace drape
