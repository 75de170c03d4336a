#pragma once
// Memory a run needs per rank, and what the rank may have: a cloth too large
// for the machine is refused up front (InputError, exit 2) instead of dying
// inside an allocation.
#include <mpi.h>

#include <cstdint>

#include "solver/scene.hpp"

namespace drape {

// Estimated peak resident bytes of one rank of `ranks` for the scene's cloth
// solved on its finest mesh: by Newton or the nonlinear CG (which holds more
// vectors), with AMRC's tree where the scene adapts or grid sequencing runs.
int64_t estimated_bytes_per_rank(const Scene& scene, int ranks);

// Bytes this rank may still have, plus what it holds now (so comparable to
// a peak RSS; max of int64_t where no limit is known): `process`, under its
// own RLIMIT_AS and RLIMIT_DATA soft limits; `node`, MemAvailable and a
// cgroup's memory.max, less their present use, which the ranks on the node
// share.
struct MemoryRoom {
  int64_t process = 0, node = 0;
};
MemoryRoom available_room();

// Throws InputError on every rank when the ranks of some node together
// need more than that node has; collective.
void check_memory(const Scene& scene, MPI_Comm comm);

}  // namespace drape
