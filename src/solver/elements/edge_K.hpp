#pragma once
// The edge (two particles a-b, a stretch element): its kinematics. The
// Evaluator's loops gather and scatter; these compute one element.
#include <cmath>

#include "solver/elements/v3.hpp"

namespace drape {

// Edge a-b: k = |xb - xa|; grad = [-u, u].
template <class T>
inline T edge_length(const V3<T>& a, const V3<T>& b, V3<T> g[2]) {
  using std::sqrt;
  const V3<T> e = b - a;
  const T L = sqrt(dot(e, e));
  const V3<T> u = (T(1) / L) * e;
  g[0] = T(-1) * u;
  g[1] = u;
  return L;
}

// The edge's kept numbers for Newton's stiffness (Evaluator::edge_kept
// writes them): e = b - a (3), |e|, 1/|e|, the frozen tension, the band
// slope over the rest length, the width.
// Its K v contributions to a and b, for the ends' moves' difference
// ed = v_b - v_a: edge_length on duals at (z, v), its eps parts written out
// in the same operations with the value parts kept, so bit for bit its
// numbers: tension times the direction's change plus the band's stiffness
// times the length's change along the direction.
inline void edge_product(const double* ke, const V3<double>& ed, V3<double> out[2]) {
  using V = V3<double>;
  const V e{ke[0], ke[1], ke[2]};
  const double Lv = ke[3], iv = ke[4];
  const V u = iv * e;
  const double dd = (ed.x * e.x + e.x * ed.x) + (ed.y * e.y + e.y * ed.y) + (ed.z * e.z + e.z * ed.z);
  const double Ld = dd / (2 * Lv);
  const double invd = (0.0 * Lv - 1.0 * Ld) / (Lv * Lv);
  const V ud{invd * e.x + iv * ed.x, invd * e.y + iv * ed.y, invd * e.z + iv * ed.z};
  const V dg[2] = {{0.0 * u.x + -1.0 * ud.x, 0.0 * u.y + -1.0 * ud.y, 0.0 * u.z + -1.0 * ud.z}, ud};
  const V vg[2] = {-1.0 * u, u};
  const double w = ke[7], tension = ke[5], stiff = ke[6] * Ld;
  for (int k = 0; k < 2; ++k) out[k] = w * (tension * dg[k] + stiff * vg[k]);
}

// The diagonal of the edge's K block at either end (the same at both),
// from its kept numbers.
inline double edge_diagonal(const double* ke) {
  const V3<double> u = ke[4] * V3<double>{ke[0], ke[1], ke[2]};  // dk/dx = -u, u: the same |.|^2
  return ke[7] * (ke[5] / ke[3] + ke[6] * dot(u, u) / 3);
}

}  // namespace drape
