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

// An edge's numbers for Newton's stiffness: e = b - a and |e| from the
// ends' positions (edge_length's operations, so its bits: recomputed by each
// product, cheaper than reading them back), then the frozen tension, the
// band slope over the rest length (kept) and the width (rest geometry).
struct EdgeStiffness {
  V3<double> e;
  double length, tension, slope_per_rest, width;
};
inline EdgeStiffness edge_stiffness(const V3<double>& a, const V3<double>& b, double tension, double slope_per_rest,
                                    double width) {
  const V3<double> e = b - a;
  return {e, root(dot(e, e)), tension, slope_per_rest, width};
}

// Its K v contribution to b (a's is its negative), for the ends' moves'
// difference ed = v_b - v_a: edge_length on duals at (z, v), its eps parts
// written out in the same operations with the value parts kept, so bit for
// bit its numbers: tension times the direction's change plus the band's
// stiffness times the length's change along the direction. T: double, or
// D4 (four edges, one in each lane).
template <class T>
inline V3<T> edge_product(const V3<T>& e, T Lv, T tension, T slope_per_rest, T w, const V3<T>& ed) {
  const T iv = num<T>(1.0) / Lv;
  const V3<T> u = iv * e;
  const T dd = (ed.x * e.x + e.x * ed.x) + (ed.y * e.y + e.y * ed.y) + (ed.z * e.z + e.z * ed.z);
  const T Ld = dd / (num<T>(2.0) * Lv);
  const T invd = (num<T>(0.0) * Lv - num<T>(1.0) * Ld) / (Lv * Lv);
  const V3<T> ud{invd * e.x + iv * ed.x, invd * e.y + iv * ed.y, invd * e.z + iv * ed.z};
  const T stiff = slope_per_rest * Ld;
  return w * (tension * ud + stiff * u);
}
inline V3<double> edge_product(const EdgeStiffness& k, const V3<double>& ed) {
  return edge_product(k.e, k.length, k.tension, k.slope_per_rest, k.width, ed);
}

// The diagonal of the edge's K block at either end (the same at both).
inline double edge_diagonal(const EdgeStiffness& k) {
  const V3<double> u = (1.0 / k.length) * k.e;  // dk/dx = -u, u: the same |.|^2
  return k.width * (k.tension / k.length + k.slope_per_rest * dot(u, u) / 3);
}

}  // namespace drape
