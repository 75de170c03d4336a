#include "solver/multigrid/block_matrix.hpp"

#include <algorithm>
#include <cmath>

namespace drape {

namespace {
inline void row_product(const BlockMatrix& A, int64_t r, const double* __restrict x, double* __restrict out) {
  const int64_t b = A.start[r];
  row_times(A.val.data() + 9 * b, A.col.data() + b, A.start[r + 1] - b, x, out);
}
}  // namespace

void BlockMatrix::multiply(const double* x, double* y) const {
#pragma omp parallel for schedule(static)
  for (int64_t r = 0; r < rows; ++r) row_product(*this, r, x, y + 3 * r);
}

void BlockMatrix::residual(const double* b, const double* x, double* res) const {
#pragma omp parallel for schedule(static)
  for (int64_t r = 0; r < rows; ++r) {
    double y[3];
    row_product(*this, r, x, y);
    for (int k = 0; k < 3; ++k) res[3 * r + k] = b[3 * r + k] - y[k];
  }
}

const double* BlockMatrix::block(int64_t r, int32_t c) const {
  const int32_t* b = col.data() + start[r];
  const int32_t* e = col.data() + start[r + 1];
  const int32_t* it = std::lower_bound(b, e, c);
  return it != e && *it == c ? &val[9 * (it - col.data())] : nullptr;
}

void BlockMatrix::set_pattern(const std::vector<std::vector<int32_t>>& cols) {
  rows = int64_t(cols.size());
  start.assign(size_t(rows) + 1, 0);
  for (int64_t r = 0; r < rows; ++r) start[r + 1] = start[r] + int64_t(cols[r].size());
  col.resize(size_t(start.back()));
  for (int64_t r = 0; r < rows; ++r) std::copy(cols[r].begin(), cols[r].end(), col.begin() + start[r]);
  val.assign(9 * col.size(), 0.0);
}

bool invert_block(const double* a, double* inv) {
  const double c00 = a[4] * a[8] - a[5] * a[7], c01 = a[5] * a[6] - a[3] * a[8], c02 = a[3] * a[7] - a[4] * a[6];
  const double det = a[0] * c00 + a[1] * c01 + a[2] * c02;
  if (!(std::abs(det) > 0) || !std::isfinite(det)) return false;
  const double id = 1.0 / det;
  inv[0] = c00 * id;
  inv[1] = (a[2] * a[7] - a[1] * a[8]) * id;
  inv[2] = (a[1] * a[5] - a[2] * a[4]) * id;
  inv[3] = c01 * id;
  inv[4] = (a[0] * a[8] - a[2] * a[6]) * id;
  inv[5] = (a[2] * a[3] - a[0] * a[5]) * id;
  inv[6] = c02 * id;
  inv[7] = (a[1] * a[6] - a[0] * a[7]) * id;
  inv[8] = (a[0] * a[4] - a[1] * a[3]) * id;
  return true;
}

}  // namespace drape
