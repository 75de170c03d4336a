#include "decomp/collective.hpp"

namespace drape {

int rank_of(MPI_Comm comm) {
  int r = 0;
  MPI_Comm_rank(comm, &r);
  return r;
}

int size_of(MPI_Comm comm) {
  int n = 1;
  MPI_Comm_size(comm, &n);
  return n;
}

bool root_decides(MPI_Comm comm, bool decision) {
  int v = decision ? 1 : 0;
  MPI_Bcast(&v, 1, MPI_INT, 0, comm);
  return v != 0;
}

int max_over_ranks(MPI_Comm comm, int value) {
  int out = value;
  MPI_Allreduce(&value, &out, 1, MPI_INT, MPI_MAX, comm);
  return out;
}

}  // namespace drape
