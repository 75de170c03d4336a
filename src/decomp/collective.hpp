#pragma once
// The few collective decisions the program's driver needs: rank 0 decides
// (its clock, its file system check) and every rank follows, so all ranks
// stop, fail or go on together and none waits in a collective alone.
#include <mpi.h>

namespace drape {

int rank_of(MPI_Comm comm);
int size_of(MPI_Comm comm);
// Rank 0's value of `decision`, on every rank.
bool root_decides(MPI_Comm comm, bool decision);
// The largest of the ranks' values, on every rank (0 from all: 0).
int max_over_ranks(MPI_Comm comm, int value);

}  // namespace drape
