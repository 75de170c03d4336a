#pragma once
// The levels' smoother: Chebyshev polynomials in D^-1 A, D the 3 x 3 block
// diagonal (one particle's block). A polynomial needs products only, no
// ordering of the particles, so it is the same operator on any thread count
// (unlike Gauss-Seidel's sweeps); the same polynomial before and after the
// coarse correction keeps the cycle symmetric, as CG's preconditioner must be.
// It damps the eigenvalues of D^-1 A in [lmax / ratio, lmax]: the coarse
// level takes the rest; lmax by power iteration, times 1.1 (ratios up to 10)
// or so that lmax + lmin is 1.21 x the estimate (above 10).
#include <vector>

#include "solver/multigrid/block_matrix.hpp"

namespace drape {

class Chebyshev {
 public:
  // Inverse diagonal blocks and the spectrum's top, for A.
  void setup(const BlockMatrix& A, int degree, double ratio);
  // x improved towards A x = b (x = 0 on entry when `zero`).
  void smooth(const BlockMatrix& A, const double* b, double* x, bool zero);
  double lambda_max() const { return lmax_; }
  // The power iteration's estimate of D^-1 A's spectral radius, and D^-1
  // (9 a row): the smoothed prolongation's step.
  double estimate() const { return estimate_; }
  const std::vector<double>& dinv() const { return dinv_; }
  // The next setup estimates lmax from scratch (no history carried).
  void forget() { eig_.clear(); }

 private:
  void apply_dinv(const double* r, double* out) const;
  std::vector<double> dinv_, r_, d_, z_, eig_;  // eig_: the power iteration's vector
  double lmax_ = 1, lmin_ = 0.1, estimate_ = 1;
  int degree_ = 2;
};

}  // namespace drape
