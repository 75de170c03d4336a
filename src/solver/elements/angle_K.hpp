#pragma once
// atan2 for the element kernels' angles (a triple's turn, a shear cell's),
// one at a time (double) or four side by side (D4): the same operations in
// every lane, so both forms give the same numbers bit for bit and the
// scalar kernels and the four-lane ones agree (as in lanes.hpp). libm's
// atan2 is a call per angle that no compiler vectorises; this one is a
// division and a polynomial, four angles per vector instruction.
// Octants: |y| and |x| ordered (lo <= hi), the angle atan(lo / hi) in
// [0, pi/4]; past pi/8 it is pi/4 + atan((lo - hi) / (lo + hi)), so one
// division leaves |t| <= tan(pi/8), where atan(t) = t + t^3 R(t^2), R a
// degree-10 polynomial interpolating (atan(t) / t - 1) / t^2 at Chebyshev
// nodes of [0, tan^2(pi/8)] (its error there 7e-18 of atan(t)). The
// octant's reflections (pi/2 - a, pi - a) add pi's parts high, then low.
// Within a few units in the last place of std::atan2
// (AngleKernel.WithinUlpsOfStdAtan2); NaN in, NaN out; atan2(0, 0) = 0.
#include <cmath>
#include <cstdint>
#include <cstring>

#include "solver/elements/lanes.hpp"
#include "solver/elements/v3.hpp"

namespace drape {

namespace angle_detail {
constexpr double kTanPi8 = 0.41421356237309503;
constexpr double kPi4 = 0.7853981633974483, kPi4Lo = 3.061616997868383e-17;
constexpr double kPi2 = 1.5707963267948966, kPi2Lo = 6.123233995736766e-17;
constexpr double kPi = 3.141592653589793, kPiLo = 1.2246467991473532e-16;
// R's coefficients, the highest degree first.
constexpr double kR[11] = {-0.01917688711906226, 0.03923165829558719, -0.0508544973794026, 0.0585814891280221,
                           -0.06664511447381948, 0.07692183190826087, -0.09090904578123903, 0.11111111015256361,
                           -0.14285714284666542, 0.1999999999999552,  -0.3333333333333333};

// The operations the lanes and the scalar take alike: select, |a|, a with
// the sign of s. Selects by comparison (false for NaN) in both forms.
inline double pick(bool c, double a, double b) { return c ? a : b; }
inline double magnitude(double a) { return std::fabs(a); }
inline double signed_as(double a, double s) { return std::copysign(a, s); }
#if DRAPE_LANES
typedef int64_t Mask4 __attribute__((vector_size(32)));
inline D4 pick(Mask4 c, D4 a, D4 b) { return c ? a : b; }
inline D4 magnitude(D4 a) { return (D4)_mm256_andnot_pd(_mm256_set1_pd(-0.0), (__m256d)a); }
inline D4 signed_as(D4 a, D4 s) {
  const __m256d sign = _mm256_set1_pd(-0.0);
  return (D4)_mm256_or_pd(_mm256_andnot_pd(sign, (__m256d)a), _mm256_and_pd(sign, (__m256d)s));
}
#endif

template <class T>
inline T atan2_of(T y, T x) {
  using angle_detail::pick;
  const T ax = magnitude(x), ay = magnitude(y);
  const auto steep = ay > ax;
  const T lo = pick(steep, ax, ay), hi = pick(steep, ay, ax);
  const auto far = lo > kTanPi8 * hi;
  const T above = pick(far, lo - hi, lo), below = pick(far, lo + hi, hi);
  const T den = pick(below == 0.0, num<T>(1.0), below);  // atan2(0, 0): 0 / 1
  const T t = above / den, t2 = t * t;
  T r = num<T>(kR[0]);
  for (int k = 1; k < 11; ++k) r = r * t2 + kR[k];
  T a = t + (t * t2) * r;
  a = pick(far, kPi4 + (a + kPi4Lo), a);
  a = pick(steep, kPi2 - (a - kPi2Lo), a);
  a = pick(x < 0.0, kPi - (a - kPiLo), a);
  a = signed_as(a, y);
  const T nan = y + x;  // NaN where either is
  return pick(nan != nan, nan, a);
}
}  // namespace angle_detail

// atan2(y, x), the kernels' form.
inline double turn_atan2(double y, double x) { return angle_detail::atan2_of(y, x); }

// Four at once: th[k] = turn_atan2(y[k], x[k]), bit for bit.
inline void turn_atan2_four(const double y[4], const double x[4], double th[4]) {
#if DRAPE_LANES
  D4 y4, x4;
  std::memcpy(&y4, y, sizeof y4);
  std::memcpy(&x4, x, sizeof x4);
  const D4 a = angle_detail::atan2_of(y4, x4);
  std::memcpy(th, &a, sizeof a);
#else
  for (int k = 0; k < 4; ++k) th[k] = turn_atan2(y[k], x[k]);
#endif
}

}  // namespace drape
