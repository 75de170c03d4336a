#pragma once
// Newton's stiffness for a triple or a cell, from its kept numbers kg: the
// slope factor (width or area times the band's frozen slope, over the rest
// length for a triple), then the strain's gradient (Evaluator::kept_gradients
// and kept_bend write them). Its K block is kg[0] g g^T: the band's
// stiffness along the strain's gradient (the indefinite geometric term is
// left out, so that K stays positive definite).
#include "solver/elements/v3.hpp"

namespace drape {

// K v's contributions to the n particles are stiff * g[k]: the slope
// factor times the moves v along the gradients g.
template <int N>
inline double rank_one_stiffness(double factor, const V3<double> g[N], const V3<double> v[N]) {
  double along = 0;
  for (int k = 0; k < N; ++k) along += dot(g[k], v[k]);
  return factor * along;
}
template <int N>
inline void rank_one_product(double factor, const V3<double> g[N], const V3<double> v[N], V3<double> out[N]) {
  const double stiff = rank_one_stiffness<N>(factor, g, v);
  for (int k = 0; k < N; ++k) out[k] = stiff * g[k];
}

// A cell's: kg holds the factor, then the gradient at each of its n particles.
template <int N>
inline void kept_gradient_product(const double* kg, const V3<double> v[N], V3<double> out[N]) {
  V3<double> g[N];
  for (int k = 0; k < N; ++k) g[k] = load3<double>(kg + 1 + 3 * k);
  rank_one_product<N>(kg[0], g, v, out);
}
// Its stiff alone: the one number a cell's buffer holds, the particles
// multiplying it by their kept gradients (kept_cell_gradient).
template <int N>
inline double kept_gradient_stiffness(const double* kg, const V3<double> v[N]) {
  V3<double> g[N];
  for (int k = 0; k < N; ++k) g[k] = load3<double>(kg + 1 + 3 * k);
  return rank_one_stiffness<N>(kg[0], g, v);
}
inline V3<double> kept_cell_gradient(const double* kg, int k) { return load3<double>(kg + 1 + 3 * k); }

// The block's diagonal entry at particle k (the mean over its three axes).
inline double kept_gradient_diagonal(const double* kg, int k) {
  const V3<double> g = load3<double>(kg + 1 + 3 * k);
  return kg[0] * dot(g, g) / 3;
}

// A triple's kept numbers: the factor, then its angle's gradients along its
// two edges, ge1 and ge2 (bend_terms): the three particles' gradients are
// -ge1, ge1 - ge2 and ge2, and recomputing them from these is bend_terms'
// own arithmetic, bit for bit: 7 numbers instead of 10.
constexpr int kKeptBend = 7;
inline void kept_bend(double factor, const V3<double> g[3], double* kg) {
  const V3<double> ge1 = -1.0 * g[0];  // exact: g[0] is -1.0 * ge1
  kg[0] = factor;
  kg[1] = ge1.x, kg[2] = ge1.y, kg[3] = ge1.z;
  kg[4] = g[2].x, kg[5] = g[2].y, kg[6] = g[2].z;
}
inline void kept_bend_gradients(const double* kg, V3<double> g[3]) {
  const V3<double> ge1 = load3<double>(kg + 1), ge2 = load3<double>(kg + 4);
  g[0] = -1.0 * ge1;
  g[1] = ge1 - ge2;
  g[2] = ge2;
}
inline void kept_bend_product(const double* kg, const V3<double> v[3], V3<double> out[3]) {
  V3<double> g[3];
  kept_bend_gradients(kg, g);
  rank_one_product<3>(kg[0], g, v, out);
}
inline double kept_bend_stiffness(const double* kg, const V3<double> v[3]) {
  V3<double> g[3];
  kept_bend_gradients(kg, g);
  return rank_one_stiffness<3>(kg[0], g, v);
}
// Particle k's gradient alone, kept_bend_gradients' g[k] bit for bit.
inline V3<double> kept_bend_gradient(const double* kg, int k) {
  if (k == 0) return -1.0 * load3<double>(kg + 1);
  if (k == 1) return load3<double>(kg + 1) - load3<double>(kg + 4);
  return load3<double>(kg + 4);
}
// Its diagonal entries at its three particles (diag[k]).
inline void kept_bend_diagonal(const double* kg, double diag[3]) {
  V3<double> g[3];
  kept_bend_gradients(kg, g);
  for (int k = 0; k < 3; ++k) diag[k] = kg[0] * dot(g[k], g[k]) / 3;
}
// diag[k] alone.
inline double kept_bend_diagonal_at(const double* kg, int k) {
  const V3<double> g = kept_bend_gradient(kg, k);
  return kg[0] * dot(g, g) / 3;
}

}  // namespace drape
