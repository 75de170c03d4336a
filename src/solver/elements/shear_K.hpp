#pragma once
// The shear cell (four particles, a leaf of the mesh): its shear angle, the
// angle's gradient, and the gradient's derivative along a direction (the
// Hessian-vector product the Newton cost's gradient needs). The templated
// kernels take Dual too: shear_cell on duals is the tests' reference for the
// hand-derived shear_cell_hv.
#include <cmath>

#include <type_traits>

#include "solver/elements/angle_K.hpp"
#include "solver/elements/lanes.hpp"
#include "solver/elements/v3.hpp"

namespace drape {

// Corner c with warp neighbour a and weft neighbour b: shear angle
// phi = pi/2 - angle(a-c, b-c) = atan2(u.v, |u x v|). Particle order [c, a, b].
// With s = |u x v|, co = u.v and s^2 + co^2 = |u|^2 |v|^2, the gradient
// along u is the part of v normal to u over s (along v alike): no cross
// products beyond s's, and one reciprocal per length.
template <class T>
inline void shear_terms(const V3<T>& c, const V3<T>& a, const V3<T>& b, V3<T> g[3], T& s, T& co) {
  using std::sqrt;
  const V3<T> u = a - c, v = b - c;
  const V3<T> w = cross(u, v);
  s = sqrt(dot(w, w));
  co = dot(u, v);
  const T is = T(1) / s, ia = T(1) / dot(u, u), ib = T(1) / dot(v, v);
  const V3<T> gu = is * (v - (co * ia) * u);
  const V3<T> gv = is * (u - (co * ib) * v);
  g[0] = T(-1) * (gu + gv);
  g[1] = gu;
  g[2] = gv;
}

// One corner's gradient (as shear_terms) and its derivative along the
// corner particles' moves r = [rc, ra, rb]: hr = H r. shear_terms' formulas
// differentiated by hand; g is shear_terms', bit for bit. T: double, or D4
// (four cells' corners, or one cell's four corners).
template <class T>
inline void shear_terms_hv(const V3<T>& c, const V3<T>& a, const V3<T>& b, const V3<T> r[3], V3<T> g[3],
                           V3<T> hr[3]) {
  using V = V3<T>;
  const V u = a - c, v = b - c;
  const V du = r[1] - r[0], dv = r[2] - r[0];
  const V w = cross(u, v);
  const T s = root(dot(w, w)), co = dot(u, v);
  const T uu = dot(u, u), vv = dot(v, v);
  const T one = num<T>(1.0), two = num<T>(2.0);
  const T is = one / s, ia = one / uu, ib = one / vv;
  const T udu = dot(u, du), vdv = dot(v, dv), dco = dot(du, v) + dot(u, dv);
  const T ds = is * (vv * udu + uu * vdv - co * dco);  // from s^2 = |u|^2 |v|^2 - co^2
  const T ka = co * ia, kb = co * ib;
  const T dka = (dco - two * ka * udu) * ia, dkb = (dco - two * kb * vdv) * ib;
  const V gu = is * (v - ka * u), gv = is * (u - kb * v);
  // d(is t) = is (dt - ds (is t)).
  const V dgu = is * ((dv - (dka * u + ka * du)) - ds * gu);
  const V dgv = is * ((du - (dkb * v + kb * dv)) - ds * gv);
  g[0] = num<T>(-1.0) * (gu + gv);
  g[1] = gu;
  g[2] = gv;
  hr[0] = num<T>(-1.0) * (dgu + dgv);
  hr[1] = dgu;
  hr[2] = dgv;
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
// Corner k's angle is the argument of z_k = s_k + i co_k, so the signed sum
// a0 - a1 - a2 + a3 is that of z0 conj(z1) z3 conj(z2): one atan2 for the
// cell instead of four (atan2 was the largest single cost of the cost
// pass). Each corner's angle lies within (-pi/2, pi/2); where both pairs'
// products have a positive real part, each pair's difference does too and
// the sum lies within (-pi, pi), atan2's range; else each pair apart.
template <class T>
inline T shear_angle_of(const T s[4], const T co[4]) {
  using std::atan2;
  const T pr = s[0] * s[1] + co[0] * co[1], pi = co[0] * s[1] - s[0] * co[1];  // z0 conj(z1)
  const T qr = s[3] * s[2] + co[3] * co[2], qi = co[3] * s[2] - s[3] * co[2];  // z3 conj(z2)
  auto angle = [](const T& y, const T& x) {
    if constexpr (std::is_same_v<T, double>)
      return turn_atan2(y, x);  // angle_K.hpp: the kernels' atan2
    else
      return atan2(y, x);
  };
  if (value(pr) > 0 && value(qr) > 0) return T(0.25) * angle(pr * qi + pi * qr, pr * qr - pi * qi);
  return T(0.25) * (angle(pi, pr) + angle(qi, qr));
}

// Four cells' angles from their corners' s and co (cell l's in s[l], co[l]),
// shear_angle_of's numbers bit for bit: where all four take its one-atan2
// form (the common case) the four atan2 in lanes (turn_atan2_four), else
// cell by cell.
inline void shear_angles_four(const double s[4][4], const double co[4][4], double phi[4]) {
  double y[4], x[4];
  bool one = true;
  for (int l = 0; l < 4; ++l) {
    const double* a = s[l];
    const double* c = co[l];
    const double pr = a[0] * a[1] + c[0] * c[1], pi = c[0] * a[1] - a[0] * c[1];
    const double qr = a[3] * a[2] + c[3] * c[2], qi = c[3] * a[2] - a[3] * c[2];
    one = one && pr > 0 && qr > 0;
    y[l] = pr * qi + pi * qr;
    x[l] = pr * qr - pi * qi;
  }
  if (!one) {
    for (int l = 0; l < 4; ++l) phi[l] = shear_angle_of(s[l], co[l]);
    return;
  }
  turn_atan2_four(y, x, phi);
  for (int l = 0; l < 4; ++l) phi[l] = 0.25 * phi[l];
}

// The corners one after another (any scalar: Dual too).
template <class T, bool Angle = true>
inline T shear_cell_scalar(const V3<T> x[4], V3<T> g[4]) {
  for (int k = 0; k < 4; ++k) g[k] = V3<T>{T(0), T(0), T(0)};
  T s[4], co[4];
  for (const ShearCorner& q : kShearCorners) {
    V3<T> gq[3];
    shear_terms(x[q.c], x[q.a], x[q.b], gq, s[q.c], co[q.c]);
    const T w = T(0.25 * q.sign);
    g[q.c] = g[q.c] + w * gq[0];
    g[q.a] = g[q.a] + w * gq[1];
    g[q.b] = g[q.b] + w * gq[2];
  }
  if constexpr (!Angle)
    return T(0);
  else
    return shear_angle_of(s, co);
}

#if DRAPE_LANES
// Corner k of kShearCorners in lane k: its corner particle is k, its
// i- and j-neighbours permute the lanes.
inline V4 shear_lanes_a(const V3<double> p[4]) { return lanes4(p, 1, 0, 3, 2); }
inline V4 shear_lanes_b(const V3<double> p[4]) { return lanes4(p, 2, 3, 0, 1); }
inline D4 shear_lane_weights() { return D4{0.25, -0.25, -0.25, 0.25}; }  // 0.25 * each corner's sign

// Adds corner contributions gq[0..2] (lanes: corners, weighted) into out,
// corner after corner as shear_cell_scalar: the same sums in the same order.
inline void shear_lanes_add(const V4 gq[3], V3<double> out[4]) {
  for (int k = 0; k < 4; ++k) out[k] = V3<double>{0, 0, 0};
  for (int q = 0; q < 4; ++q) {
    const ShearCorner& c = kShearCorners[q];
    out[c.c] = out[c.c] + lane(gq[0], q);
    out[c.a] = out[c.a] + lane(gq[1], q);
    out[c.b] = out[c.b] + lane(gq[2], q);
  }
}

// shear_cell_scalar on doubles with the four corners' shear_terms in lanes:
// its numbers bit for bit (tests: ShearLanes.*).
// shear_cell_lanes' gradient, and its corners' s and co (shear_angle_of's
// arguments) in place of the angle.
inline void shear_cell_terms(const V3<double> x[4], V3<double> g[4], double s_out[4], double co_out[4]) {
  const V4 xc = lanes4(x, 0, 1, 2, 3);
  const V4 u = shear_lanes_a(x) - xc, v = shear_lanes_b(x) - xc;
  const V4 w = cross(u, v);
  const D4 s = sqrt4(dot(w, w)), co = dot(u, v);
  const D4 one = splat4(1.0), wt = shear_lane_weights();
  const D4 is = one / s, ia = one / dot(u, u), ib = one / dot(v, v);
  const V4 gu = is * (v - (co * ia) * u);
  const V4 gv = is * (u - (co * ib) * v);
  const V4 gq[3] = {wt * (splat4(-1.0) * (gu + gv)), wt * gu, wt * gv};
  shear_lanes_add(gq, g);
  storeu4(s_out, s);
  storeu4(co_out, co);
}

template <bool Angle>
inline double shear_cell_lanes(const V3<double> x[4], V3<double> g[4]) {
  double sa[4], ca[4];
  shear_cell_terms(x, g, sa, ca);
  if constexpr (!Angle)
    return 0.0;
  else
    return shear_angle_of(sa, ca);
}

#endif

// The cell's angle and gradient: on doubles the lanes' kernel (with
// DRAPE_LANES), else the scalar one.
template <class T, bool Angle = true>
inline T shear_cell(const V3<T> x[4], V3<T> g[4]) {
#if DRAPE_LANES
  if constexpr (std::is_same_v<T, double>) return shear_cell_lanes<Angle>(x, g);
#endif
  return shear_cell_scalar<T, Angle>(x, g);
}

// The cell's gradient (shear_cell's, bit for bit) and its derivative along
// the corners' moves r: hr = H r. The corners one after another.
inline void shear_cell_hv_scalar(const V3<double> x[4], const V3<double> r[4], V3<double> g[4],
                                 V3<double> hr[4]) {
  using V = V3<double>;
  for (int k = 0; k < 4; ++k) g[k] = hr[k] = V{0, 0, 0};
  for (const ShearCorner& q : kShearCorners) {
    const V rq[3] = {r[q.c], r[q.a], r[q.b]};
    V gq[3], hq[3];
    shear_terms_hv(x[q.c], x[q.a], x[q.b], rq, gq, hq);
    const double w = 0.25 * q.sign;
    const int at[3] = {q.c, q.a, q.b};
    for (int k = 0; k < 3; ++k) {
      g[at[k]] = g[at[k]] + w * gq[k];
      hr[at[k]] = hr[at[k]] + w * hq[k];
    }
  }
}

// shear_cell_hv_scalar with the four corners' shear_terms_hv in lanes
// (DRAPE_LANES; else the scalar kernel): its numbers bit for bit (tests:
// ShearLanes.*).
inline void shear_cell_hv(const V3<double> x[4], const V3<double> r[4], V3<double> g[4], V3<double> hr[4]) {
#if !DRAPE_LANES
  shear_cell_hv_scalar(x, r, g, hr);
#else
  const V4 rq[3] = {lanes4(r, 0, 1, 2, 3), shear_lanes_a(r), shear_lanes_b(r)};
  V4 gq[3], hq[3];
  shear_terms_hv(lanes4(x, 0, 1, 2, 3), shear_lanes_a(x), shear_lanes_b(x), rq, gq, hq);
  const D4 wt = shear_lane_weights();
  for (int k = 0; k < 3; ++k) {
    gq[k] = wt * gq[k];
    hq[k] = wt * hq[k];
  }
  shear_lanes_add(gq, g);
  shear_lanes_add(hq, hr);
#endif
}

#if DRAPE_LANES
// Four cells side by side, cell l in lane l: X[k], R[k] corner k's positions
// and moves, G[k], H[k] its gradient and H r. shear_cell_hv_scalar's
// operations in its order (the corners one after another), lane by lane:
// its numbers bit for bit, without the shuffles that put one cell's corners
// in lanes and add them back (tests: ShearLanes.*).
inline void shear_cells_hv_four(const V4 X[4], const V4 R[4], V4 G[4], V4 H[4]) {
  const V4 zero{splat4(0.0), splat4(0.0), splat4(0.0)};
  for (int k = 0; k < 4; ++k) G[k] = H[k] = zero;
  for (const ShearCorner& q : kShearCorners) {
    const V4 rq[3] = {R[q.c], R[q.a], R[q.b]};
    V4 gq[3], hq[3];
    shear_terms_hv(X[q.c], X[q.a], X[q.b], rq, gq, hq);
    const D4 w = splat4(0.25 * q.sign);
    const int at[3] = {q.c, q.a, q.b};
    for (int k = 0; k < 3; ++k) {
      G[at[k]] = G[at[k]] + w * gq[k];
      H[at[k]] = H[at[k]] + w * hq[k];
    }
  }
}

// shear_cells_hv_four on cell-by-cell arrays (cell l's corners x[l], moves
// r[l]; its gradient g[l] and H r hr[l]).
inline void shear_cells_hv_four(const V3<double> x[4][4], const V3<double> r[4][4], V3<double> g[4][4],
                                V3<double> hr[4][4]) {
  V4 X[4], R[4], G[4], H[4];
  for (int k = 0; k < 4; ++k) {
    const V3<double> xk[4] = {x[0][k], x[1][k], x[2][k], x[3][k]}, rk[4] = {r[0][k], r[1][k], r[2][k], r[3][k]};
    X[k] = lanes4(xk);
    R[k] = lanes4(rk);
  }
  shear_cells_hv_four(X, R, G, H);
  for (int l = 0; l < 4; ++l)
    for (int k = 0; k < 4; ++k) {
      g[l][k] = lane(G[k], l);
      hr[l][k] = lane(H[k], l);
    }
}
#endif

}  // namespace drape
