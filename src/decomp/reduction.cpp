#include "decomp/reduction.hpp"

#include <algorithm>

namespace drape {

MpiReducer::MpiReducer(MPI_Comm comm, int total_tiles) : comm_(comm), tiles_(total_tiles) {}

void MpiReducer::sum_tiles(const std::vector<int>& owned, const double* partials, int k,
                           double* out) const {
  const double t0 = MPI_Wtime();
  global_.assign(size_t(k) * tiles_, 0.0);
  const size_t n = owned.size();
  for (int r = 0; r < k; ++r)
    for (size_t t = 0; t < n; ++t) global_[size_t(r) * tiles_ + owned[t]] = partials[r * n + t];
  MPI_Allreduce(MPI_IN_PLACE, global_.data(), k * tiles_, MPI_DOUBLE, MPI_SUM, comm_);
  for (int r = 0; r < k; ++r) {
    double s = 0;
    for (int t = 0; t < tiles_; ++t) s += global_[size_t(r) * tiles_ + t];
    out[r] = s;
  }
  seconds += MPI_Wtime() - t0;
}

double MpiReducer::max(double v) const {
  const double t0 = MPI_Wtime();
  MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_DOUBLE, MPI_MAX, comm_);
  seconds += MPI_Wtime() - t0;
  return v;
}

uint64_t MpiReducer::sum_u64(uint64_t v) const {
  MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_UINT64_T, MPI_SUM, comm_);
  return v;
}

int64_t MpiReducer::sum_i64(int64_t v) const {
  MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_INT64_T, MPI_SUM, comm_);
  return v;
}

void MpiReducer::max_each(double* a, int64_t n) const {
  const double t0 = MPI_Wtime();
  const int64_t piece = int64_t(1) << 30;  // MPI counts are int
  for (int64_t k = 0; k < n; k += piece)
    MPI_Allreduce(MPI_IN_PLACE, a + k, int(std::min(piece, n - k)), MPI_DOUBLE, MPI_MAX, comm_);
  seconds += MPI_Wtime() - t0;
}

}  // namespace drape
