#pragma once
// Newton's stiffness for a triple or a cell, from its kept numbers kg: the
// slope factor (width or area times the band's frozen slope, over the rest
// length for a triple), then the strain's gradient at each of its n
// particles (Evaluator::kept_gradients writes them). Its K block is
// kg[0] g g^T: the band's stiffness along the strain's gradient (the
// indefinite geometric term is left out, so that K stays positive definite).
#include "solver/elements/v3.hpp"

namespace drape {

// K v's contributions to the n particles, for their moves v.
template <int N>
inline void kept_gradient_product(const double* kg, const V3<double> v[N], V3<double> out[N]) {
  V3<double> g[N];
  for (int k = 0; k < N; ++k) g[k] = load3<double>(kg + 1 + 3 * k);
  double along = 0;
  for (int k = 0; k < N; ++k) along += dot(g[k], v[k]);
  const double stiff = kg[0] * along;
  for (int k = 0; k < N; ++k) out[k] = stiff * g[k];
}

// The block's diagonal entry at particle k (the mean over its three axes).
inline double kept_gradient_diagonal(const double* kg, int k) {
  const V3<double> g = load3<double>(kg + 1 + 3 * k);
  return kg[0] * dot(g, g) / 3;
}

}  // namespace drape
