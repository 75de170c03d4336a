#pragma once
// The edge (two particles a-b, a stretch element): its kinematics. The
// Evaluator's loops gather and scatter; these compute one element.
#include <cmath>

#include "solver/elements/lanes.hpp"
#include "solver/elements/v3.hpp"

namespace drape {

// Edge a-b: k = |xb - xa|; grad = [-u, u].
template <class T>
inline T edge_length(const V3<T>& a, const V3<T>& b, V3<T> g[2]) {
  const V3<T> e = b - a;
  const T L = root(dot(e, e));
  const V3<T> u = (num<T>(1.0) / L) * e;
  g[0] = num<T>(-1.0) * u;
  g[1] = u;
  return L;
}

// edge_length, and its Hessian times the ends' moves' difference v = rb - ra:
// hv = (v - u (u.v)) / L (the derivative of u along v).
template <class T>
inline T edge_length_hv(const V3<T>& a, const V3<T>& b, const V3<T>& v, V3<T> g[2], V3<T>& hv) {
  const T L = edge_length(a, b, g);
  hv = (num<T>(1.0) / L) * (v - dot(g[1], v) * g[1]);
  return L;
}

// Four edges side by side: edge k's ends a[k], b[k] (and moves' difference
// v[k]) in lane k, the scalar kernels' numbers bit for bit (tests:
// EdgeLanes.*): one vector square root and division for four. Without
// DRAPE_LANES, the scalar kernels one edge after another.
struct EdgeFour {
  V3<double> a[4], b[4];
};

inline void edge_length_four(const EdgeFour& e, V3<double> g[4][2], double L[4]) {
#if DRAPE_LANES
  V4 g4[2];
  const D4 L4 = edge_length(lanes4(e.a), lanes4(e.b), g4);
  for (int k = 0; k < 4; ++k) {
    g[k][0] = lane(g4[0], k);
    g[k][1] = lane(g4[1], k);
    L[k] = L4[k];
  }
#else
  for (int k = 0; k < 4; ++k) L[k] = edge_length(e.a[k], e.b[k], g[k]);
#endif
}

inline void edge_length_hv_four(const EdgeFour& e, const V3<double> v[4], V3<double> g[4][2], double L[4],
                                V3<double> hv[4]) {
#if DRAPE_LANES
  V4 g4[2], h4;
  const D4 L4 = edge_length_hv(lanes4(e.a), lanes4(e.b), lanes4(v), g4, h4);
  for (int k = 0; k < 4; ++k) {
    g[k][0] = lane(g4[0], k);
    g[k][1] = lane(g4[1], k);
    L[k] = L4[k];
    hv[k] = lane(h4, k);
  }
#else
  for (int k = 0; k < 4; ++k) L[k] = edge_length_hv(e.a[k], e.b[k], v[k], g[k], hv[k]);
#endif
}

// The edge's kept numbers for Newton's stiffness (Evaluator::edge_kept
// writes them): e = b - a (3), |e|, the frozen tension, the band slope over
// the rest length, the width. 1/|e| is computed again, the same division
// (edge_length's): one number fewer held.
// Its K v contributions to a and b, for the ends' moves' difference
// ed = v_b - v_a: edge_length on duals at (z, v), its eps parts written out
// in the same operations with the value parts kept, so bit for bit its
// numbers: tension times the direction's change plus the band's stiffness
// times the length's change along the direction.
inline void edge_product(const double* ke, const V3<double>& ed, V3<double> out[2]) {
  using V = V3<double>;
  const V e{ke[0], ke[1], ke[2]};
  const double Lv = ke[3], iv = 1.0 / Lv;
  const V u = iv * e;
  const double dd = (ed.x * e.x + e.x * ed.x) + (ed.y * e.y + e.y * ed.y) + (ed.z * e.z + e.z * ed.z);
  const double Ld = dd / (2 * Lv);
  const double invd = (0.0 * Lv - 1.0 * Ld) / (Lv * Lv);
  const V ud{invd * e.x + iv * ed.x, invd * e.y + iv * ed.y, invd * e.z + iv * ed.z};
  const V dg[2] = {{0.0 * u.x + -1.0 * ud.x, 0.0 * u.y + -1.0 * ud.y, 0.0 * u.z + -1.0 * ud.z}, ud};
  const V vg[2] = {-1.0 * u, u};
  const double w = ke[6], tension = ke[4], stiff = ke[5] * Ld;
  for (int k = 0; k < 2; ++k) out[k] = w * (tension * dg[k] + stiff * vg[k]);
}

// The diagonal of the edge's K block at either end (the same at both),
// from its kept numbers.
inline double edge_diagonal(const double* ke) {
  const V3<double> u = (1.0 / ke[3]) * V3<double>{ke[0], ke[1], ke[2]};  // dk/dx = -u, u: the same |.|^2
  return ke[6] * (ke[4] / ke[3] + ke[5] * dot(u, u) / 3);
}

}  // namespace drape
