#include "decomp/reduction.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

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

namespace {

// An element-wise reduction in place, in pieces (MPI counts are int).
template <class T>
void reduce_each(T* a, int64_t n, MPI_Datatype type, MPI_Op op, MPI_Comm comm) {
  const int64_t piece = int64_t(1) << 30;
  for (int64_t k = 0; k < n; k += piece) MPI_Allreduce(MPI_IN_PLACE, a + k, int(std::min(piece, n - k)), type, op, comm);
}

}  // namespace

void MpiReducer::max_each(double* a, int64_t n) const {
  const double t0 = MPI_Wtime();
  reduce_each(a, n, MPI_DOUBLE, MPI_MAX, comm_);
  seconds += MPI_Wtime() - t0;
}

void MpiReducer::or_each(uint32_t* a, int64_t n) const {
  const double t0 = MPI_Wtime();
  reduce_each(a, n, MPI_UINT32_T, MPI_BOR, comm_);
  seconds += MPI_Wtime() - t0;
}

int MpiReducer::ranks() const {
  int n = 1;
  MPI_Comm_size(comm_, &n);
  return n;
}

void MpiReducer::counts(int64_t n, std::vector<int64_t>& out) const {
  out.resize(size_t(ranks()));
  MPI_Allgather(&n, 1, MPI_INT64_T, out.data(), 1, MPI_INT64_T, comm_);
}

// Round k moves bytes [k kPiece, (k + 1) kPiece) of every rank's part into
// round_, whence each lands at its rank's offset in `all`.
void MpiReducer::gather_bytes(const void* mine, const std::vector<int64_t>& bytes, void* all) const {
  const double t0 = MPI_Wtime();
  const int n = int(bytes.size());
  int me = 0;
  MPI_Comm_rank(comm_, &me);
  int64_t most = 0;
  std::vector<int64_t>& at = at_;  // members: no allocation per V-cycle
  std::vector<int>&cnt = cnt_, &disp = disp_;
  at.assign(size_t(n) + 1, 0);
  cnt.resize(size_t(n));
  disp.resize(size_t(n));
  for (int k = 0; k < n; ++k) {
    most = std::max(most, bytes[k]);
    at[k + 1] = at[k] + bytes[k];
  }
  for (int64_t from = 0; from < most; from += kPiece) {
    int64_t total = 0;
    for (int k = 0; k < n; ++k) {
      cnt[k] = int(std::clamp<int64_t>(bytes[k] - from, 0, kPiece));
      disp[k] = int(total);
      total += cnt[k];
    }
    if (round_.size() < size_t(total)) round_.resize(size_t(total));
    MPI_Allgatherv(static_cast<const char*>(mine) + (cnt[me] > 0 ? from : 0), cnt[me], MPI_BYTE, round_.data(),
                   cnt.data(), disp.data(), MPI_BYTE, comm_);
    for (int k = 0; k < n; ++k)
      if (cnt[k] > 0) std::memcpy(static_cast<char*>(all) + at[k] + from, round_.data() + disp[k], size_t(cnt[k]));
  }
  seconds += MPI_Wtime() - t0;
}

int MpiReducer::rank() const {
  int me = 0;
  MPI_Comm_rank(comm_, &me);
  return me;
}

void MpiReducer::exchange_bytes(const void* send, const std::vector<int64_t>& send_bytes, void* recv,
                                const std::vector<int64_t>& recv_bytes) const {
  const double t0 = MPI_Wtime();
  const int n = int(send_bytes.size());
  cnt_.resize(size_t(n));
  disp_.resize(size_t(n));
  rcnt_.resize(size_t(n));
  rdisp_.resize(size_t(n));
  int64_t s = 0, r = 0;
  for (int k = 0; k < n; ++k) {
    if (s + send_bytes[k] > INT32_MAX || r + recv_bytes[k] > INT32_MAX)
      throw std::runtime_error("MpiReducer::exchange_bytes: over 2 GiB in one exchange");
    cnt_[k] = int(send_bytes[k]);
    disp_[k] = int(s);
    rcnt_[k] = int(recv_bytes[k]);
    rdisp_[k] = int(r);
    s += send_bytes[k];
    r += recv_bytes[k];
  }
  MPI_Alltoallv(send, cnt_.data(), disp_.data(), MPI_BYTE, recv, rcnt_.data(), rdisp_.data(), MPI_BYTE, comm_);
  seconds += MPI_Wtime() - t0;
}

}  // namespace drape
