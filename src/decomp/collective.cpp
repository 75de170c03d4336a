#include "decomp/collective.hpp"

#include <algorithm>
#include <cstdlib>
#include <iostream>

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

int ranks_on_node(MPI_Comm comm) {
  MPI_Comm node = MPI_COMM_NULL;
  MPI_Comm_split_type(comm, MPI_COMM_TYPE_SHARED, rank_of(comm), MPI_INFO_NULL, &node);
  const int n = size_of(node);
  MPI_Comm_free(&node);
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

unsigned or_over_ranks(MPI_Comm comm, unsigned value) {
  unsigned out = value;
  MPI_Allreduce(&value, &out, 1, MPI_UNSIGNED, MPI_BOR, comm);
  return out;
}

uint64_t sum_over_ranks(MPI_Comm comm, uint64_t value) {
  uint64_t out = value;
  MPI_Allreduce(&value, &out, 1, MPI_UINT64_T, MPI_SUM, comm);
  return out;
}

std::string root_error(MPI_Comm comm, const std::string& error) {
  char text[512] = {0};
  std::copy_n(error.data(), std::min(error.size(), sizeof text - 1), text);
  MPI_Bcast(text, sizeof text, MPI_CHAR, 0, comm);
  return text;
}

std::string first_error(MPI_Comm comm, const std::string& error) {
  const int size = size_of(comm);
  int mine = error.empty() ? size : rank_of(comm), first = size;
  MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, comm);
  if (first == size) return "";
  char text[512] = {0};
  std::copy_n(error.data(), std::min(error.size(), sizeof text - 1), text);
  MPI_Bcast(text, sizeof text, MPI_CHAR, first, comm);
  return text;
}

void wait_for_all(MPI_Comm comm) { MPI_Barrier(comm); }

void end_all_ranks(MPI_Comm comm, const std::string& what) {
  std::cerr << "drape: error: rank " << rank_of(comm) << " of " << size_of(comm) << ": internal: " << what
            << std::endl;
  MPI_Abort(comm, 1);
  std::abort();  // MPI_Abort does not return; this tells the compiler so
}

}  // namespace drape
