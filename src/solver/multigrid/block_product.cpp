#include "solver/multigrid/block_product.hpp"

#include <algorithm>
#include <vector>

namespace drape {

namespace {
// out += a b (3 x 3, row-major).
inline void add_product(const double* __restrict a, const double* __restrict b, double* __restrict out) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out[3 * i + j] += a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

void product_pattern(const BlockMatrix& A, const BlockMatrix& B, BlockMatrix& C) {
  std::vector<std::vector<int32_t>> cols(size_t(A.rows));
#pragma omp parallel for schedule(static)
  for (int64_t r = 0; r < A.rows; ++r) {
    std::vector<int32_t>& c = cols[r];
    for (int64_t k = A.start[r]; k < A.start[r + 1]; ++k) {
      const int64_t g = A.col[k];
      c.insert(c.end(), B.col.begin() + B.start[g], B.col.begin() + B.start[g + 1]);
    }
    std::sort(c.begin(), c.end());
    c.erase(std::unique(c.begin(), c.end()), c.end());
  }
  C.set_pattern(cols);
}
}  // namespace

void block_product(const BlockMatrix& A, const BlockMatrix& B, int64_t cols, BlockMatrix& C, bool pattern) {
  if (pattern) product_pattern(A, B, C);
#pragma omp parallel
  {
    // Each thread's map from a column to its block in the current row: set
    // for the row's pattern, cleared after it (no searches).
    std::vector<int64_t> slot(size_t(cols), -1);
#pragma omp for schedule(static)
    for (int64_t r = 0; r < A.rows; ++r) {
      for (int64_t k = C.start[r]; k < C.start[r + 1]; ++k) slot[C.col[k]] = k;
      std::fill(C.val.begin() + 9 * C.start[r], C.val.begin() + 9 * C.start[r + 1], 0.0);
      for (int64_t k = A.start[r]; k < A.start[r + 1]; ++k) {
        const int64_t g = A.col[k];
        const double* a = &A.val[9 * k];
        for (int64_t b = B.start[g]; b < B.start[g + 1]; ++b) add_product(a, &B.val[9 * b], &C.val[9 * slot[B.col[b]]]);
      }
      for (int64_t k = C.start[r]; k < C.start[r + 1]; ++k) slot[C.col[k]] = -1;
    }
  }
}

}  // namespace drape
