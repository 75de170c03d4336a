#pragma once
// The coarsest level solved directly: a sparse LDL^T of the assembled
// (symmetric positive definite) coarse operator, factored once per setup.
// Its own, so that nothing is allocated once its arrays are sized: the
// ordering (minimum degree on the 3 x 3 blocks' graph), the elimination
// tree and L's column counts are computed when the pattern changes, into
// arrays that only grow; each factorisation writes L's values in place
// (up-looking, row by row), and a solve works in a kept vector. Every sum
// runs in an order fixed by the pattern: the same factors on any thread count.
#include <cstdint>
#include <vector>

#include "solver/multigrid/block_matrix.hpp"

namespace drape {

class CoarseSolve {
 public:
  // Analyses A's pattern when `pattern`, then factors A's values (A's
  // pattern must be the one last analysed otherwise).
  void factor(const BlockMatrix& A, bool pattern);
  // x = A^-1 b (3 doubles a row of A); x may be b.
  void solve(const double* b, double* x);
  // The bytes its factor, ordering and workspaces hold.
  size_t held_bytes() const {
    size_t b = 0;
    for (const auto* v : {&perm_, &inv_, &ap_, &ai_, &from_, &parent_, &lp_, &lnz_, &li_, &stack_, &flag_, &degree_})
      b += v->capacity() * sizeof(int64_t);
    for (const auto* v : {&ax_, &lx_, &d_, &y_}) b += v->capacity() * sizeof(double);
    return b + (adj_.capacity() + alive_.capacity()) * sizeof(uint64_t);
  }
  // L's stored entries (below its unit diagonal): what the ordering saved.
  int64_t factor_entries() const { return lp_.empty() ? 0 : lp_.back(); }

 private:
  void order_blocks(const BlockMatrix& A);
  void set_pattern(const BlockMatrix& A);
  void symbolic();

  int64_t n_ = 0;                  // scalar unknowns, 3 a block row
  std::vector<int64_t> perm_;      // factor's unknown k is A's unknown perm_[k]
  std::vector<int64_t> inv_;       // A's unknown u is the factor's inv_[u]
  // The permuted operator's upper triangle by columns (diagonal included),
  // each entry's value read from A.val[from_[p]].
  std::vector<int64_t> ap_, ai_, from_;
  std::vector<double> ax_;
  // L (unit lower, diagonal not stored) by columns, and D.
  std::vector<int64_t> parent_, lp_, lnz_, li_;
  std::vector<double> lx_, d_;
  // Workspaces: the row being eliminated, its pattern, the visit marks,
  // and the ordering's bit sets of the blocks' graph.
  std::vector<double> y_;
  std::vector<int64_t> stack_, flag_;
  std::vector<uint64_t> adj_, alive_;
  std::vector<int64_t> degree_;
};

}  // namespace drape
