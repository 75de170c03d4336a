#include "solver/multigrid/smoothed_prolongation.hpp"

#include "solver/multigrid/block_product.hpp"

namespace drape {

void smooth_prolongation(const BlockMatrix& A, const std::vector<double>& dinv, double lmax, const Prolongation& P0,
                         BlockMatrix& AP0, Prolongation& P, bool pattern) {
  block_product(A, P0.P, P0.coarse(), AP0, pattern);
  BlockMatrix& S = P.P;
  if (pattern) {
    // AP0's pattern holds P0's (A has its diagonal).
    S.rows = AP0.rows;
    S.start = AP0.start;
    S.col = AP0.col;
    S.val.assign(AP0.val.size(), 0.0);
  }
  const double w = 4.0 / (3.0 * lmax);
#pragma omp parallel for schedule(static)
  for (int64_t f = 0; f < S.rows; ++f) {
    const double* di = &dinv[9 * f];
    int64_t k0 = P0.P.start[f];
    for (int64_t k = S.start[f]; k < S.start[f + 1]; ++k) {
      double* s = &S.val[9 * k];
      const double* ap = &AP0.val[9 * k];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          s[entry(i, j)] = -w * (di[3 * i] * ap[entry(0, j)] + di[3 * i + 1] * ap[entry(1, j)] + di[3 * i + 2] * ap[entry(2, j)]);
      if (k0 < P0.P.start[f + 1] && P0.P.col[k0] == S.col[k]) {
        for (int i = 0; i < 9; ++i) s[i] += P0.P.val[9 * k0 + i];
        ++k0;
      }
    }
  }
  transpose(S, P0.coarse(), P.T);
}

}  // namespace drape
