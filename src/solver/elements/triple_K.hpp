#pragma once
// The triple (three particles a-b-c along a mesh line, a bending element):
// its angle, gradient, and the gradient's derivative along a direction (the
// Hessian-vector product the Newton cost's gradient needs). The templated
// kernels take Dual too: bend_gradient on duals is the tests' reference for
// the hand-derived bend_gradient_hv.
#include <cmath>
#include <type_traits>

#include "solver/elements/angle_K.hpp"
#include "solver/elements/lanes.hpp"
#include "solver/elements/v3.hpp"

namespace drape {

// Triple a-b-c: signed turning angle at b about the frozen axis n (unit),
// between the edges projected on the plane normal to n:
// theta = atan2((e1 x e2).n, e1p.e2p). Only bending out of the cloth's plane
// (about n) counts; the axis is set from the step's history (docs/design.md §1).
// Projected, atan2's arguments vanish only when an edge lies along n (an
// in-plane right-angle turn); with the plain e1.e2 they vanished at any
// right-angle turn about an axis normal to n, which grid-scale crumples at
// a hanging corner reach (a 49 x 49 drape stalled there; projected it passes).
// bend_terms gives the gradient and the atan2 arguments; bend_gradient is for
// passes that need no angle (atan2 is a large share of the work).
template <class T>
inline void bend_terms(const V3<T>& a, const V3<T>& b, const V3<T>& c, const V3<T>& n, V3<T> g[3],
                       T& s, T& co) {
  const V3<T> e1 = b - a, e2 = c - b;
  const V3<T> e1p = e1 - dot(e1, n) * n, e2p = e2 - dot(e2, n) * n;
  s = dot(cross(e1, e2), n);
  co = dot(e1p, e2p);
  const T inv = num<T>(1.0) / (s * s + co * co);
  const V3<T> ge1 = inv * (co * cross(e2, n) - s * e2p);
  const V3<T> ge2 = inv * (co * cross(n, e1) - s * e1p);
  g[0] = num<T>(-1.0) * ge1;
  g[1] = ge1 - ge2;
  g[2] = ge2;
}
template <class T>
inline T bend_angle(const V3<T>& a, const V3<T>& b, const V3<T>& c, const V3<T>& n, V3<T> g[3]) {
  T s, co;
  bend_terms(a, b, c, n, g, s, co);
  if constexpr (std::is_same_v<T, double>) {
    return turn_atan2(s, co);  // as the four-lane pass's (angle_K.hpp)
  } else {
    using std::atan2;
    return atan2(s, co);
  }
}
template <class T>
inline void bend_gradient(const V3<T>& a, const V3<T>& b, const V3<T>& c, const V3<T>& n, V3<T> g[3]) {
  T s, co;
  bend_terms(a, b, c, n, g, s, co);
}

// The gradient g of the angle and its derivative along r (r[k] moves
// particle k): hr = H r, H the angle's Hessian. bend_terms' formulas
// differentiated by hand, term by term; g is bend_gradient's, bit for bit.
// About half the arithmetic of bend_gradient on duals (no zero eps parts of
// n and the constants, one reciprocal). T: double, or D4 (four triples).
template <class T>
inline void bend_gradient_hv(const V3<T>& a, const V3<T>& b, const V3<T>& c, const V3<T>& n, const V3<T> r[3],
                             V3<T> g[3], V3<T> hr[3]) {
  using V = V3<T>;
  const V e1 = b - a, e2 = c - b;
  const V de1 = r[1] - r[0], de2 = r[2] - r[1];
  const V e1p = e1 - dot(e1, n) * n, e2p = e2 - dot(e2, n) * n;
  const V de1p = de1 - dot(de1, n) * n, de2p = de2 - dot(de2, n) * n;
  const T s = dot(cross(e1, e2), n), co = dot(e1p, e2p);
  const V A1 = cross(e2, n), A2 = cross(n, e1);  // s = e1.A1 = e2.A2
  // ds = (de1 x e2 + e1 x de2).n; e2p and e1p lie normal to n.
  const T ds = dot(de1, A1) + dot(de2, A2), dco = dot(de1, e2p) + dot(e1p, de2);
  const T inv = num<T>(1.0) / (s * s + co * co);
  const T dinv = num<T>(-2.0) * inv * inv * (s * ds + co * dco);
  const V t1 = co * A1 - s * e2p, t2 = co * A2 - s * e1p;
  const V ge1 = inv * t1, ge2 = inv * t2;
  const V dt1 = dco * A1 + co * cross(de2, n) - (ds * e2p + s * de2p);
  const V dt2 = dco * A2 + co * cross(n, de1) - (ds * e1p + s * de1p);
  const V dge1 = dinv * t1 + inv * dt1, dge2 = dinv * t2 + inv * dt2;
  g[0] = num<T>(-1.0) * ge1;
  g[1] = ge1 - ge2;
  g[2] = ge2;
  hr[0] = num<T>(-1.0) * dge1;
  hr[1] = dge1 - dge2;
  hr[2] = dge2;
}

// Four triples side by side: triple k's particles a[k], b[k], c[k], axis
// n[k] (and moves r[k]) in lane k. The scalar kernels' numbers bit for bit
// (tests: TripleLanes.*): each lane does their operations in their order,
// one vector division for four. Without DRAPE_LANES, the scalar kernels one
// triple after another.
struct TripleFour {
  V3<double> a[4], b[4], c[4], n[4];
};

// bend_terms of the four: g[k], s[k], co[k] triple k's.
inline void bend_terms_four(const TripleFour& t, V3<double> g[4][3], double s[4], double co[4]) {
#if DRAPE_LANES
  V4 g4[3];
  D4 s4, co4;
  bend_terms(lanes4(t.a), lanes4(t.b), lanes4(t.c), lanes4(t.n), g4, s4, co4);
  for (int k = 0; k < 4; ++k) {
    for (int i = 0; i < 3; ++i) g[k][i] = lane(g4[i], k);
    s[k] = s4[k];
    co[k] = co4[k];
  }
#else
  for (int k = 0; k < 4; ++k) bend_terms(t.a[k], t.b[k], t.c[k], t.n[k], g[k], s[k], co[k]);
#endif
}

// bend_gradient_hv of the four, r[k] triple k's moves.
inline void bend_gradient_hv_four(const TripleFour& t, const V3<double> r[4][3], V3<double> g[4][3],
                                  V3<double> hr[4][3]) {
#if DRAPE_LANES
  V4 r4[3], g4[3], h4[3];
  for (int i = 0; i < 3; ++i) {
    const V3<double> ri[4] = {r[0][i], r[1][i], r[2][i], r[3][i]};
    r4[i] = lanes4(ri);
  }
  bend_gradient_hv(lanes4(t.a), lanes4(t.b), lanes4(t.c), lanes4(t.n), r4, g4, h4);
  for (int k = 0; k < 4; ++k)
    for (int i = 0; i < 3; ++i) {
      g[k][i] = lane(g4[i], k);
      hr[k][i] = lane(h4[i], k);
    }
#else
  for (int k = 0; k < 4; ++k) bend_gradient_hv(t.a[k], t.b[k], t.c[k], t.n[k], r[k], g[k], hr[k]);
#endif
}

}  // namespace drape
