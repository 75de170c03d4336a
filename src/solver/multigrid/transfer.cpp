#include "solver/multigrid/transfer.hpp"

#include <algorithm>

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
  Prolongation P;
  P.fine = int64_t(fine_ids.size());
  P.coarse = int64_t(coarse_ids.size());
  for (size_t k = 0; k < coarse_ids.size(); ++k) scratch[coarse_ids[k]] = int32_t(k);
  P.start.assign(size_t(P.fine) + 1, 0);
  for (int64_t f = 0; f < P.fine; ++f) {
    const int64_t p = fine_ids[f];
    int ii[2], jj[2];
    double wi[2], wj[2];
    const int ni_ = line_weights(int(p / nj), ni, stride, ii, wi);
    const int nj_ = line_weights(int(p % nj), nj, stride, jj, wj);
    for (int a = 0; a < ni_; ++a)
      for (int b = 0; b < nj_; ++b) {
        const int32_t c = scratch[int64_t(ii[a]) * nj + jj[b]];
        if (c < 0) continue;  // not an unknown: no correction from there
        P.col.push_back(c);
        P.w.push_back(wi[a] * wj[b]);
      }
    P.start[f + 1] = int64_t(P.col.size());
  }
  for (int64_t p : coarse_ids) scratch[p] = -1;
  // The transpose, fine points ascending in each coarse point's list.
  P.t_start.assign(size_t(P.coarse) + 1, 0);
  for (int32_t c : P.col) ++P.t_start[c + 1];
  for (int64_t c = 0; c < P.coarse; ++c) P.t_start[c + 1] += P.t_start[c];
  P.t_row.resize(P.col.size());
  P.t_w.resize(P.col.size());
  std::vector<int64_t> fill(P.t_start.begin(), P.t_start.end() - 1);
  for (int64_t f = 0; f < P.fine; ++f)
    for (int64_t k = P.start[f]; k < P.start[f + 1]; ++k) {
      P.t_row[fill[P.col[k]]] = int32_t(f);
      P.t_w[fill[P.col[k]]++] = P.w[k];
    }
  return P;
}

void prolong_add(const Prolongation& P, const double* xc, double* xf) {
#pragma omp parallel for schedule(static)
  for (int64_t f = 0; f < P.fine; ++f)
    for (int64_t k = P.start[f]; k < P.start[f + 1]; ++k)
      for (int d = 0; d < 3; ++d) xf[3 * f + d] += P.w[k] * xc[3 * int64_t(P.col[k]) + d];
}

void restrict_to(const Prolongation& P, const double* rf, double* bc) {
#pragma omp parallel for schedule(static)
  for (int64_t c = 0; c < P.coarse; ++c) {
    double s[3] = {0, 0, 0};
    for (int64_t k = P.t_start[c]; k < P.t_start[c + 1]; ++k)
      for (int d = 0; d < 3; ++d) s[d] += P.t_w[k] * rf[3 * int64_t(P.t_row[k]) + d];
    for (int d = 0; d < 3; ++d) bc[3 * c + d] = s[d];
  }
}

void galerkin(const BlockMatrix& A, const Prolongation& P, BlockMatrix& Ac, bool pattern) {
  // Row I of P^T A P: over the fine points f that I interpolates to, their
  // blocks A(f, g), and g's coarse points J.
  auto terms = [&](int64_t I, auto&& add) {
    for (int64_t a = P.t_start[I]; a < P.t_start[I + 1]; ++a) {
      const int64_t f = P.t_row[a];
      const double wf = P.t_w[a];
      for (int64_t k = A.start[f]; k < A.start[f + 1]; ++k) {
        const int64_t g = A.col[k];
        const double* blk = &A.val[9 * k];
        for (int64_t b = P.start[g], e = P.start[g + 1]; b < e; ++b) add(P.col[b], wf * P.w[b], blk);
      }
    }
  };
  if (pattern) {
    std::vector<std::vector<int32_t>> cols(size_t(P.coarse));
#pragma omp parallel for schedule(static)
    for (int64_t I = 0; I < P.coarse; ++I) {
      terms(I, [&](int32_t J, double, const double*) { cols[I].push_back(J); });
      std::sort(cols[I].begin(), cols[I].end());
      cols[I].erase(std::unique(cols[I].begin(), cols[I].end()), cols[I].end());
    }
    Ac.set_pattern(cols);
  }
#pragma omp parallel
  {
    // Each thread's map from a coarse column to its block in the current
    // row: set for the row's pattern, cleared after it (no searches).
    std::vector<int64_t> slot(size_t(P.coarse), -1);
#pragma omp for schedule(static)
    for (int64_t I = 0; I < P.coarse; ++I) {
      for (int64_t k = Ac.start[I]; k < Ac.start[I + 1]; ++k) slot[Ac.col[k]] = k;
      std::fill(Ac.val.begin() + 9 * Ac.start[I], Ac.val.begin() + 9 * Ac.start[I + 1], 0.0);
      double* __restrict val = Ac.val.data();
      terms(I, [&](int32_t J, double w, const double* __restrict blk) {
        double* __restrict out = val + 9 * slot[J];
        for (int i = 0; i < 9; ++i) out[i] += w * blk[i];
      });
      for (int64_t k = Ac.start[I]; k < Ac.start[I + 1]; ++k) slot[Ac.col[k]] = -1;
    }
  }
}

}  // namespace drape
