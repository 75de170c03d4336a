#pragma once
// Per-element kinematics, kept apart from the loops that drive them (AMReX
// style). Each kernel returns the element's kinematic measure k (edge length,
// bending angle, shear angle) and writes dk/dx for each of its particles.
// Templated on the scalar so that a Dual argument gives H*v in the eps part.
#include <cmath>

#include "solver/dual.hpp"

namespace drape {

template <class T>
struct V3 {
  T x, y, z;
};
template <class T>
inline V3<T> operator+(const V3<T>& a, const V3<T>& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
template <class T>
inline V3<T> operator-(const V3<T>& a, const V3<T>& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <class T>
inline V3<T> operator*(T s, const V3<T>& a) { return {s * a.x, s * a.y, s * a.z}; }
template <class T>
inline T dot(const V3<T>& a, const V3<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <class T>
inline V3<T> cross(const V3<T>& a, const V3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T>
inline V3<T> load3(const double* p) { return {T(p[0]), T(p[1]), T(p[2])}; }
inline V3<Dual> load3(const double* p, const double* v) {
  return {Dual(p[0], v[0]), Dual(p[1], v[1]), Dual(p[2], v[2])};
}
template <class T>
inline void store3(const V3<T>& a, T* out) { out[0] = a.x; out[1] = a.y; out[2] = a.z; }

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
  const T inv = T(1) / (s * s + co * co);
  const V3<T> ge1 = inv * (co * cross(e2, n) - s * e2p);
  const V3<T> ge2 = inv * (co * cross(n, e1) - s * e1p);
  g[0] = T(-1) * ge1;
  g[1] = ge1 - ge2;
  g[2] = ge2;
}
template <class T>
inline T bend_angle(const V3<T>& a, const V3<T>& b, const V3<T>& c, const V3<T>& n, V3<T> g[3]) {
  using std::atan2;
  T s, co;
  bend_terms(a, b, c, n, g, s, co);
  return atan2(s, co);
}
template <class T>
inline void bend_gradient(const V3<T>& a, const V3<T>& b, const V3<T>& c, const V3<T>& n, V3<T> g[3]) {
  T s, co;
  bend_terms(a, b, c, n, g, s, co);
}

// Corner c with warp neighbour a and weft neighbour b: shear angle
// phi = pi/2 - angle(a-c, b-c) = atan2(u.v, |u x v|). Particle order [c, a, b].
template <class T>
inline void shear_terms(const V3<T>& c, const V3<T>& a, const V3<T>& b, V3<T> g[3], T& s, T& co) {
  using std::sqrt;
  const V3<T> u = a - c, v = b - c;
  const V3<T> w = cross(u, v);
  s = sqrt(dot(w, w));
  co = dot(u, v);
  const T inv = T(1) / (s * s + co * co);
  const T is = T(1) / s;
  const V3<T> gu = inv * (s * v - (co * is) * cross(v, w));
  const V3<T> gv = inv * (s * u - (co * is) * cross(w, u));
  g[0] = T(-1) * (gu + gv);
  g[1] = gu;
  g[2] = gv;
}

// Shear of a cell [s, a (along i), b (along j), d (across)]: the mean of its
// four corner angles, signed so that one in-plane shear reads alike in all
// four. Read per cell, an in-plane zigzag of the mesh lines shears every
// cell; read per particle (the mean over its four quadrants) it cancelled,
// an hourglass mode that let a 129 x 129 drape's lines kink in 43 % of their
// neighbouring pairs. Corners as (corner, its i-neighbour, its j-neighbour, sign).
struct ShearCorner {
  int c, a, b;
  double sign;
};
inline constexpr ShearCorner kShearCorners[4] = {{0, 1, 2, 1.0}, {1, 0, 3, -1.0}, {2, 3, 0, -1.0}, {3, 2, 1, 1.0}};

// Returns the angle when Angle is set (else 0: the gradient alone skips atan2).
template <class T, bool Angle = true>
inline T shear_cell(const V3<T> x[4], V3<T> g[4]) {
  using std::atan2;
  for (int k = 0; k < 4; ++k) g[k] = V3<T>{T(0), T(0), T(0)};
  T phi = T(0);
  for (const ShearCorner& q : kShearCorners) {
    V3<T> gq[3];
    T s, co;
    shear_terms(x[q.c], x[q.a], x[q.b], gq, s, co);
    const T w = T(0.25 * q.sign);
    g[q.c] = g[q.c] + w * gq[0];
    g[q.a] = g[q.a] + w * gq[1];
    g[q.b] = g[q.b] + w * gq[2];
    if constexpr (Angle) phi = phi + w * atan2(co, s);
  }
  return phi;
}

}  // namespace drape
