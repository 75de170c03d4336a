#pragma once
// A sparse matrix of 3 x 3 blocks, one block row per particle (compressed
// rows): the assembled stiffness K and the multigrid's coarse operators.
// Rows are independent, so products split over threads with results that do
// not depend on how (each row sums its blocks in column order).
#include <cstdint>
#include <vector>

namespace drape {

struct BlockMatrix {
  int64_t rows = 0;
  std::vector<int64_t> start;  // rows + 1: row r's blocks are [start[r], start[r+1])
  std::vector<int32_t> col;    // block column, ascending within a row
  std::vector<double> val;     // 9 per block, row-major

  int64_t blocks() const { return start.empty() ? 0 : start.back(); }
  // y = A x (3 doubles a row).
  void multiply(const double* x, double* y) const;
  // r = b - A x.
  void residual(const double* b, const double* x, double* r) const;
  // The block at (r, c); null where there is none.
  const double* block(int64_t r, int32_t c) const;
  double* block(int64_t r, int32_t c) {
    return const_cast<double*>(static_cast<const BlockMatrix*>(this)->block(r, c));
  }
  // Rows from per-row column lists (ascending, distinct); values zero.
  void set_pattern(const std::vector<std::vector<int32_t>>& cols);
};

// y += s * B x for one 3 x 3 block.
inline void add_block_times(const double* b, const double* x, double s, double* y) {
  for (int i = 0; i < 3; ++i) y[i] += s * (b[3 * i] * x[0] + b[3 * i + 1] * x[1] + b[3 * i + 2] * x[2]);
}

// The inverse of a symmetric positive definite 3 x 3 block (by cofactors);
// false where it is not invertible.
bool invert_block(const double* a, double* inv);

}  // namespace drape
