#include "solver/multigrid/transfer.hpp"

#include <algorithm>
#include <utility>

#include "solver/multigrid/block_product.hpp"

namespace drape {

namespace {
// Whether grid line i (of n) is one of the lines of stride s.
inline bool on_lines(int i, int n, int s) { return i % s == 0 || i == n - 1; }
// Line i's neighbours on the lines of stride 2s and their weights (1 or 2).
inline int line_weights(int i, int n, int s, int idx[2], double w[2]) {
  if (on_lines(i, n, 2 * s)) {
    idx[0] = i;
    w[0] = 1;
    return 1;
  }
  const int lo = i - s, hi = std::min(i + s, n - 1);
  idx[0] = lo;
  idx[1] = hi;
  w[0] = double(hi - i) / (hi - lo);
  w[1] = double(i - lo) / (hi - lo);
  return 2;
}
}  // namespace

std::vector<int64_t> coarse_points(const std::vector<int64_t>& ids, int ni, int nj, int stride) {
  std::vector<int64_t> out;
  for (int64_t p : ids)
    if (on_lines(int(p / nj), ni, 2 * stride) && on_lines(int(p % nj), nj, 2 * stride)) out.push_back(p);
  return out;
}

Prolongation make_prolongation(const std::vector<int64_t>& fine_ids, const std::vector<int64_t>& coarse_ids, int ni,
                               int nj, int stride, std::vector<int32_t>& scratch) {
  Prolongation out;
  BlockMatrix& P = out.P;
  P.rows = int64_t(fine_ids.size());
  for (size_t k = 0; k < coarse_ids.size(); ++k) scratch[coarse_ids[k]] = int32_t(k);
  P.start.assign(size_t(P.rows) + 1, 0);
  for (int64_t f = 0; f < P.rows; ++f) {
    const int64_t p = fine_ids[f];
    int ii[2], jj[2];
    double wi[2], wj[2];
    const int ni_ = line_weights(int(p / nj), ni, stride, ii, wi);
    const int nj_ = line_weights(int(p % nj), nj, stride, jj, wj);
    std::vector<std::pair<int32_t, double>> row;
    for (int a = 0; a < ni_; ++a)
      for (int b = 0; b < nj_; ++b) {
        const int32_t c = scratch[int64_t(ii[a]) * nj + jj[b]];
        if (c >= 0) row.emplace_back(c, wi[a] * wj[b]);  // else not an unknown: no correction from there
      }
    std::sort(row.begin(), row.end());
    for (const auto& [c, w] : row) {
      P.col.push_back(c);
      const double blk[9] = {w, 0, 0, 0, w, 0, 0, 0, w};
      P.val.insert(P.val.end(), blk, blk + 9);
    }
    P.start[f + 1] = int64_t(P.col.size());
  }
  for (int64_t p : coarse_ids) scratch[p] = -1;
  transpose(P, int64_t(coarse_ids.size()), out.T);
  out.scalar = true;
  return out;
}

void transpose(const BlockMatrix& P, int64_t coarse, BlockMatrix& T) {
  T.rows = coarse;
  T.start.assign(size_t(coarse) + 1, 0);
  for (int32_t c : P.col) ++T.start[c + 1];
  for (int64_t c = 0; c < coarse; ++c) T.start[c + 1] += T.start[c];
  T.col.resize(P.col.size());
  T.val.resize(P.val.size());
  std::vector<int64_t> fill(T.start.begin(), T.start.end() - 1);
  for (int64_t f = 0; f < P.rows; ++f)
    for (int64_t k = P.start[f]; k < P.start[f + 1]; ++k) {
      const int64_t t = fill[P.col[k]]++;
      T.col[t] = int32_t(f);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) T.val[9 * t + 3 * j + i] = P.val[9 * k + 3 * i + j];
    }
}

void prolong_add(const Prolongation& P, const double* xc, double* xf) {
  const BlockMatrix& M = P.P;
  if (P.scalar) {
#pragma omp parallel for schedule(static)
    for (int64_t f = 0; f < M.rows; ++f)
      for (int64_t k = M.start[f]; k < M.start[f + 1]; ++k) {
        const double w = M.val[9 * k];
        const double* x = xc + 3 * int64_t(M.col[k]);
        for (int i = 0; i < 3; ++i) xf[3 * f + i] += w * x[i];
      }
    return;
  }
#pragma omp parallel for schedule(static)
  for (int64_t f = 0; f < M.rows; ++f)
    for (int64_t k = M.start[f]; k < M.start[f + 1]; ++k)
      add_stored_block_times(&M.val[9 * k], xc + 3 * int64_t(M.col[k]), xf + 3 * f);
}

void restrict_to(const Prolongation& P, const double* rf, double* bc) {
  if (!P.scalar) {
    P.T.multiply(rf, bc);
    return;
  }
  const BlockMatrix& T = P.T;
#pragma omp parallel for schedule(static)
  for (int64_t c = 0; c < T.rows; ++c) {
    double y0 = 0, y1 = 0, y2 = 0;  // row_times' sums, w's zeros left out
    for (int64_t k = T.start[c]; k < T.start[c + 1]; ++k) {
      const double w = T.val[9 * k];
      const double* x = rf + 3 * int64_t(T.col[k]);
      y0 += w * x[0];
      y1 += w * x[1];
      y2 += w * x[2];
    }
    bc[3 * c] = y0;
    bc[3 * c + 1] = y1;
    bc[3 * c + 2] = y2;
  }
}

void galerkin(const BlockMatrix& A, const Prolongation& P, BlockMatrix& AP, BlockMatrix& Ac, bool pattern) {
  if (P.scalar) {
    block_product_scalar_right(A, P.P, P.coarse(), AP, pattern);
    block_product_scalar_left(P.T, AP, P.coarse(), Ac, pattern);
    return;
  }
  block_product(A, P.P, P.coarse(), AP, pattern);
  block_product(P.T, AP, P.coarse(), Ac, pattern);
}

}  // namespace drape
