#pragma once
// The multigrid's finest level on several ranks: every rank's free
// particles, in the order one rank lists them (tile, then index), and
// vectors (and, where the finest level is not divided, K's rows) gathered
// into it, so that every rank works on the one-rank numbers (bitwise the
// one-rank result). The product's vectors stay split; the whole cycle
// gathers its right-hand side (3 doubles a free particle) and each rank
// takes its own rows of the result.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "mesh/tiles.hpp"
#include "solver/multigrid/block_matrix.hpp"
#include "solver/reducer.hpp"

namespace drape {

// Every rank's rows of a block matrix (global columns), concatenated in
// rank order, into one matrix whose row g is the concatenation's row
// from[g]: the ranks' rows whole, in one order, on every rank. Collective.
// Returns the bytes this rank received (8 a row, 4 + 72 a block).
int64_t gather_rows(const Reducer& red, const BlockMatrix& mine, const std::vector<int64_t>& rows_per_rank,
                    const std::vector<int64_t>& from, BlockMatrix& all);

class RankRows {
 public:
  // From this rank's free particles `mine` (its list order; `grid` particles
  // in all): the global order and its maps. Collective.
  void number(const Reducer& red, const Tiling& tiling, const std::vector<int64_t>& mine, int64_t grid);
  int64_t size() const { return int64_t(ids_.size()); }
  // All free particles, one rank's order.
  const std::vector<int64_t>& ids() const { return ids_; }
  // Grid particle -> its global row (-1: not free): K's columns.
  const std::vector<int32_t>& column_of() const { return column_of_; }
  // Every rank's rows of `mine` (global columns) in global order. Collective.
  void gather_matrix(const Reducer& red, const BlockMatrix& mine, BlockMatrix& all);
  // Every rank's 3 doubles a row of `mine` into `all`, in global order. Collective.
  void gather(const Reducer& red, const double* mine, double* all);
  // This rank's row r's global row.
  const std::vector<int64_t>& mine() const { return mine_; }
  // The rank whose row global row g is.
  int owner(int64_t g) const {
    return int(std::upper_bound(first_.begin(), first_.end(), from_[size_t(g)]) - first_.begin()) - 1;
  }
  // This rank's rows of a global vector.
  void take_mine(const double* all, double* mine) const;
  // Bytes this rank received in the last gather_matrix, and a gather's.
  int64_t matrix_bytes() const { return matrix_bytes_; }
  int64_t vector_bytes() const { return 24 * size(); }
  size_t memory() const;

 private:
  std::vector<int64_t> ids_, rows_;  // rows_: rows per rank
  std::vector<int64_t> from_;        // global row -> its row in the ranks' concatenation
  std::vector<int64_t> first_;       // per rank: its first row in the concatenation
  std::vector<int64_t> mine_;        // this rank's row -> global row
  std::vector<int32_t> column_of_;
  std::vector<int64_t> blocks_, bytes_;
  std::vector<double> cat_;  // the vectors' concatenation
  int64_t matrix_bytes_ = 0;
};

}  // namespace drape
