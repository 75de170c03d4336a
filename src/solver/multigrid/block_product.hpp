#pragma once
// C = A B for matrices of 3 x 3 blocks (A's columns are B's rows): the
// Galerkin product's two halves and the smoothed prolongation's A P. Row r
// of C sums, for A's blocks in column order, B's row blocks in column order:
// a fixed order, the same matrix on any thread count.
#include <cstdint>

#include "solver/multigrid/block_matrix.hpp"

namespace drape {

// `cols`: B's column count. C's pattern is set when `pattern` (else kept).
void block_product(const BlockMatrix& A, const BlockMatrix& B, int64_t cols, BlockMatrix& C, bool pattern);
// The same where B's (right) or A's (left) blocks are all w I: the same sums
// bit for bit (add_block_product's other terms are exact zeros), w read alone.
void block_product_scalar_right(const BlockMatrix& A, const BlockMatrix& B, int64_t cols, BlockMatrix& C, bool pattern);
void block_product_scalar_left(const BlockMatrix& A, const BlockMatrix& B, int64_t cols, BlockMatrix& C, bool pattern);

}  // namespace drape
