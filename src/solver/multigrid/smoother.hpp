#pragma once
// The levels' smoother: Chebyshev polynomials in D^-1 A, D the 3 x 3 block
// diagonal (one particle's block). A polynomial needs products only, no
// ordering of the particles, so it is the same operator on any thread count
// (unlike Gauss-Seidel's sweeps); the same polynomial before and after the
// coarse correction keeps the cycle symmetric, as CG's preconditioner must be.
// It damps the eigenvalues of D^-1 A in [lmax / ratio, lmax]: the coarse
// level takes the rest; lmax by power iteration, times 1.1 (ratios up to 10)
// or so that lmax + lmin is 1.21 x the estimate (above 10).
#include <cstdint>
#include <vector>

#include "solver/multigrid/block_matrix.hpp"

namespace drape {

// Sum of squares in index order (thread and rank counts do not matter): the
// power iteration's norm, one rank's or gathered whole.
inline double ordered_norm2(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x * x;
  return s;
}

class Chebyshev {
 public:
  // Inverse diagonal blocks and the spectrum's top, for A.
  void setup(const BlockMatrix& A, int degree, double ratio);
  // x improved towards A x = b (x = 0 on entry when `zero`).
  void smooth(const BlockMatrix& A, const double* b, double* x, bool zero);
  // The same polynomial on `rows` rows of A whose products another holds
  // (a rank's rows: DividedLevel): residual(x, r) sets r = b - A x there,
  // dinv(i) is row i's inverse diagonal block; r, d, z: 3 doubles a row.
  // The same operations in the same order as smooth.
  template <class Residual, class Dinv>
  void smooth_rows(int64_t rows, const double* b, double* x, bool zero, Residual&& residual, Dinv&& dinv, double* r,
                   double* d, double* z) const;
  double lambda_max() const { return lmax_; }
  int degree() const { return degree_; }
  // The power iteration's estimate of D^-1 A's spectral radius, and D^-1
  // (9 a row): the smoothed prolongation's step.
  double estimate() const { return estimate_; }
  const std::vector<double>& dinv() const { return dinv_; }
  size_t held_bytes() const {
    return (dinv_.capacity() + r_.capacity() + d_.capacity() + z_.capacity() + eig_.capacity()) * sizeof(double);
  }
  // The next setup estimates lmax from scratch (no history carried).
  void forget() { eig_.clear(); }
  // The polynomial for a spectrum estimate made elsewhere (a level divided
  // over ranks: DividedLevel), as setup sets it from its own.
  void set_spectrum(int degree, double ratio, double estimate);
  // The power iteration's cold start, entry i (3 a row).
  static double start_entry(int64_t i) { return 1.0 + 0.1 * double((i * 7) % 13); }
  // Power iteration steps: cold (from start_entry), warm (from the last set-up's vector).
  static constexpr int cold_steps = 12, warm_steps = 3;

 private:
  template <class Dinv>
  static void apply_dinv(int64_t rows, Dinv&& dinv, const double* r, double* out);
  std::vector<double> dinv_, r_, d_, z_, eig_;  // eig_: the power iteration's vector
  double lmax_ = 1, lmin_ = 0.1, estimate_ = 1;
  int degree_ = 2;
};

template <class Dinv>
void Chebyshev::apply_dinv(int64_t rows, Dinv&& dinv, const double* r, double* out) {
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < rows; ++i) {
    const double* m = dinv(i);
    const double* x = r + 3 * i;
    for (int k = 0; k < 3; ++k) out[3 * i + k] = m[3 * k] * x[0] + m[3 * k + 1] * x[1] + m[3 * k + 2] * x[2];
  }
}

// Chebyshev acceleration of x += D^-1 (b - A x) (Saad, Iterative Methods
// for Sparse Linear Systems, 2nd ed., Algorithm 12.1, preconditioned).
template <class Residual, class Dinv>
void Chebyshev::smooth_rows(int64_t rows, const double* b, double* x, bool zero, Residual&& residual, Dinv&& dinv,
                            double* r, double* d, double* z) const {
  const int64_t m = 3 * rows;
  const double theta = 0.5 * (lmax_ + lmin_), delta = 0.5 * (lmax_ - lmin_);
  const double sigma = theta / delta;
  double rho = 1 / sigma;
  if (zero)
    for (int64_t i = 0; i < m; ++i) r[i] = b[i];
  else
    residual(x, r);
  apply_dinv(rows, dinv, r, d);
  for (int64_t i = 0; i < m; ++i) d[i] /= theta;
  for (int k = 0; k < degree_; ++k) {
    if (zero && k == 0)
      for (int64_t i = 0; i < m; ++i) x[i] = d[i];
    else
      for (int64_t i = 0; i < m; ++i) x[i] += d[i];
    if (k + 1 == degree_) break;
    residual(x, r);
    const double rho1 = 1 / (2 * sigma - rho);
    const double c1 = rho1 * rho, c2 = 2 * rho1 / delta;
    apply_dinv(rows, dinv, r, z);
    for (int64_t i = 0; i < m; ++i) d[i] = c1 * d[i] + c2 * z[i];
    rho = rho1;
  }
}

}  // namespace drape
