#pragma once
// Reductions across ranks in a fixed order (docs/design.md §3). Each tile's partial
// is non-zero on exactly one rank, so an MPI sum over a vector indexed by
// global tile id is exact (x + 0 = x); the tiles are then summed in tile
// order on every rank. Bitwise the same on any number of ranks.
#include <mpi.h>

#include "solver/reducer.hpp"

namespace drape {

class MpiReducer : public Reducer {
 public:
  MpiReducer(MPI_Comm comm, int total_tiles);
  void sum_tiles(const std::vector<int>& owned, const double* partials, int k,
                 double* out) const override;
  double max(double v) const override;
  uint64_t sum_u64(uint64_t v) const override;
  int64_t sum_i64(int64_t v) const override;
  void max_each(double* a, int64_t n) const override;
  void or_each(uint32_t* a, int64_t n) const override;
  int ranks() const override;
  void counts(int64_t n, std::vector<int64_t>& out) const override;
  // In rounds of at most kPiece bytes a rank (MPI's counts are int).
  void gather_bytes(const void* mine, const std::vector<int64_t>& bytes, void* all) const override;
  int rank() const override;
  // One MPI_Alltoallv (the parts are small: a level's rows next to a rank's).
  void exchange_bytes(const void* send, const std::vector<int64_t>& send_bytes, void* recv,
                      const std::vector<int64_t>& recv_bytes) const override;

  mutable double seconds = 0;  // in its collectives but the integer sums and counts, this rank

 private:
  MPI_Comm comm_;
  int tiles_;
  mutable std::vector<double> global_;
  static constexpr int64_t kPiece = int64_t(1) << 26;
  mutable std::vector<char> round_;  // one round's pieces, rank after rank
  mutable std::vector<int64_t> at_;
  mutable std::vector<int> cnt_, disp_, rcnt_, rdisp_;
};

}  // namespace drape
