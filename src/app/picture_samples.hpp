#pragma once
// The picture's samples (io/picture.hpp) on rank 0, sent by the owners of
// the positions they read: at most about 400 x 400 samples and their
// brackets, whatever the grid, so rank 0 holds no whole-cloth array.
#include <mpi.h>

#include <vector>

#include "io/picture.hpp"
#include "mesh/tiles.hpp"

namespace drape {

// x: 3 per grid particle, read only at this rank's tiles' particles. On
// rank 0, `out` holds the samples. False on every rank where a position
// read is not finite: its bracket would be the next finite one along the
// line, which only the whole cloth tells. values_received: rank 0's count.
// Collective.
bool picture_samples_on_root(const PicturePlan& plan, const double* x, const Tiling& tiling,
                             const std::vector<int>& owner, MPI_Comm comm, PictureSurface& out,
                             size_t* values_received = nullptr);

}  // namespace drape
