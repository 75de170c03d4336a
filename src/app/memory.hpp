#pragma once
// Memory a run needs per rank, and what the rank may have: a cloth too large
// for the machine is refused up front (InputError, exit 2) instead of dying
// inside an allocation.
#include <mpi.h>

#include <cstdint>

#include "solver/scene.hpp"

namespace drape {

// Estimated peak resident bytes of one rank of `ranks` for a grid of n
// particles, solved by Newton or by the nonlinear CG (which holds more vectors).
int64_t estimated_bytes_per_rank(int64_t n, int ranks, bool nonlinear_cg);

// Bytes this rank may still have, plus what it holds now (so comparable to
// a peak RSS): the least of MemAvailable, the RLIMIT_AS and RLIMIT_DATA soft
// limits and a cgroup's memory.max, each less its present use.
int64_t available_bytes();

// Throws InputError on every rank when any rank's estimate exceeds what it
// has; collective.
void check_memory(const Scene& scene, MPI_Comm comm);

}  // namespace drape
