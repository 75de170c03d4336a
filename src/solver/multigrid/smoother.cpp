#include "solver/multigrid/smoother.hpp"

#include <cmath>
#include <stdexcept>

namespace drape {

void Chebyshev::setup(const BlockMatrix& A, int degree, double ratio) {
  degree_ = degree;
  const int64_t n = A.rows;
  dinv_.assign(9 * size_t(n), 0.0);
  r_.assign(3 * size_t(n), 0.0);
  d_.assign(3 * size_t(n), 0.0);
  z_.assign(3 * size_t(n), 0.0);
  bool ok = true;
#pragma omp parallel for schedule(static) reduction(&& : ok)
  for (int64_t i = 0; i < n; ++i) {
    const double* a = A.block(i, int32_t(i));
    ok = ok && a && invert_stored_block(a, &dinv_[9 * i]);
  }
  if (!ok) throw std::runtime_error("multigrid: a particle's diagonal block is singular");
  // Power iteration on D^-1 A: from a fixed start after forget() or on a new
  // pattern (12 steps), else from the last set-up's vector (the operator
  // moved a little: 3 steps). Too few steps from a cold start underestimate
  // lmax, and the polynomial then amplifies the spectrum's top (6 steps at
  // 129 x 129 took a solve from 30 iterations to 237).
  int steps = warm_steps;
  if (eig_.size() != size_t(3 * n)) {
    eig_.resize(size_t(3 * n));
    for (int64_t i = 0; i < 3 * n; ++i) eig_[i] = start_entry(i);
    steps = cold_steps;
  }
  double lam = 1;
  for (int it = 0; it < steps; ++it) {
    const double nd = std::sqrt(ordered_norm2(eig_));
    if (!(nd > 0)) break;
    for (double& x : eig_) x /= nd;
    A.multiply(eig_.data(), r_.data());
    apply_dinv(n, [&](int64_t i) { return &dinv_[9 * i]; }, r_.data(), eig_.data());
    lam = std::sqrt(ordered_norm2(eig_));
  }
  set_spectrum(degree, ratio, lam);
}

void Chebyshev::set_spectrum(int degree, double ratio, double lam) {
  degree_ = degree;
  estimate_ = lam;
  // The polynomial amplifies every eigenvalue above lmax + lmin (its
  // residual passes -1 or +1 there), and then the V-cycle is no longer
  // positive definite: CG's r.s turns negative and the solve diverges to
  // NaN. The power iteration approaches lmax from below: 12 cold steps are
  // 5-12 % low on the drape's levels at 65 x 65 (3.31 against 3.49 on the
  // finest, 2.14 against 2.39 on the third), 11 % on a Laplacian, and 3
  // warm steps may be further off. With lmax = 1.1 x the estimate, lmax +
  // lmin is 1.21 x it at ratio 10 but 1.14 x at ratio 30 and 1.12 x at 50
  // (the Laplacian's top mode then grows). So lmax + lmin stays 1.21 x the
  // estimate at any ratio above 10 (up to 10 as it was).
  const double margin = ratio <= 10 ? 1.1 : 1.21 * ratio / (ratio + 1);
  lmax_ = margin * lam;
  lmin_ = lmax_ / ratio;
}

void Chebyshev::smooth(const BlockMatrix& A, const double* b, double* x, bool zero) {
  smooth_rows(
      A.rows, b, x, zero, [&](const double* y, double* r) { A.residual(b, y, r); },
      [&](int64_t i) { return &dinv_[9 * i]; }, r_.data(), d_.data(), z_.data());
}

}  // namespace drape
