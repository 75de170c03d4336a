#include "solver/multigrid/block_product.hpp"

#include <omp.h>

#include <algorithm>
#include <vector>

namespace drape {

namespace {
// The scratch of the calling thread's products (the products run one at a
// time from it): kept between calls so that rebuilt patterns allocate nothing.
struct ProductScratch {
  PatternScratch pattern;
  SlotMaps slots;
};
ProductScratch& scratch() {
  static thread_local ProductScratch s;
  return s;
}

void product_pattern(const BlockMatrix& A, const BlockMatrix& B, BlockMatrix& C) {
  build_pattern(C, A.rows, scratch().pattern, [&](int64_t r, auto&& push) {
    for (int64_t k = A.start[r]; k < A.start[r + 1]; ++k) {
      const int64_t g = A.col[k];
      for (int64_t b = B.start[g]; b < B.start[g + 1]; ++b) push(B.col[b]);
    }
  });
}
}  // namespace

namespace {
// C = A B with `add(a, b, c)` adding block a times block b into c: row r's
// sums in A's then B's column order, whatever the blocks' kind.
template <class Add>
void product_rows(const BlockMatrix& A, const BlockMatrix& B, int64_t cols, BlockMatrix& C, bool pattern, Add&& add) {
  if (pattern) product_pattern(A, B, C);
  SlotMaps& slots = scratch().slots;
  slots.size(omp_get_max_threads(), cols);
#pragma omp parallel
  {
    // This thread's map from a column to its block in the current row: set
    // for the row's pattern, cleared after it (no searches).
    std::vector<int64_t>& slot = slots.of[size_t(omp_get_thread_num())];
#pragma omp for schedule(static)
    for (int64_t r = 0; r < A.rows; ++r) {
      for (int64_t k = C.start[r]; k < C.start[r + 1]; ++k) slot[C.col[k]] = k;
      std::fill(C.val.begin() + 9 * C.start[r], C.val.begin() + 9 * C.start[r + 1], 0.0);
      for (int64_t k = A.start[r]; k < A.start[r + 1]; ++k) {
        const int64_t g = A.col[k];
        const double* a = &A.val[9 * k];
        for (int64_t b = B.start[g]; b < B.start[g + 1]; ++b) add(a, &B.val[9 * b], &C.val[9 * slot[B.col[b]]]);
      }
      for (int64_t k = C.start[r]; k < C.start[r + 1]; ++k) slot[C.col[k]] = -1;
    }
  }
}
}  // namespace

void block_product(const BlockMatrix& A, const BlockMatrix& B, int64_t cols, BlockMatrix& C, bool pattern) {
  product_rows(A, B, cols, C, pattern, [](const double* a, const double* b, double* c) { add_block_product(a, b, c); });
}

void block_product_scalar_right(const BlockMatrix& A, const BlockMatrix& B, int64_t cols, BlockMatrix& C,
                                bool pattern) {
  product_rows(A, B, cols, C, pattern, [](const double* a, const double* b, double* c) { add_scaled_block(b[0], a, c); });
}

void block_product_scalar_left(const BlockMatrix& A, const BlockMatrix& B, int64_t cols, BlockMatrix& C,
                               bool pattern) {
  product_rows(A, B, cols, C, pattern, [](const double* a, const double* b, double* c) { add_scaled_block(a[0], b, c); });
}

}  // namespace drape
