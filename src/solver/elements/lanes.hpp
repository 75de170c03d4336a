#pragma once
// Four doubles as one value (GCC's and Clang's vector extension), for the
// kernels that compute four like things side by side (a shear cell's
// corners, four triples, four edges). Every lane does the scalar kernel's
// operations in its order: IEEE division and square root round alike in
// either form and -ffp-contract=off keeps products and sums apart, so the
// lanes give the scalar results bit for bit, with one vector division or
// square root in place of four dependent scalar ones.
// With AVX only (the build's -march=native has it where the CPU does):
// without it a 32-byte vector would pass in memory, and the kernels take
// their scalar forms, the same numbers. DRAPE_LANES says which.
#if defined(__AVX__)
#define DRAPE_LANES 1
#include <immintrin.h>

#include "solver/elements/v3.hpp"

namespace drape {

typedef double D4 __attribute__((vector_size(32)));
using V4 = V3<D4>;  // lane k: the k-th of the four vectors

inline D4 splat4(double a) { return D4{a, a, a, a}; }
template <>
inline D4 num<D4>(double a) { return splat4(a); }

inline D4 sqrt4(D4 a) { return (D4)_mm256_sqrt_pd((__m256d)a); }
// Four consecutive doubles, at any alignment.
inline D4 loadu4(const double* p) { return (D4)_mm256_loadu_pd(p); }
inline void storeu4(double* p, D4 a) { _mm256_storeu_pd(p, (__m256d)a); }
template <>
inline D4 root<D4>(D4 a) { return sqrt4(a); }

// The vectors p[i0..i3] as lanes.
inline V4 lanes4(const V3<double> p[4], int i0, int i1, int i2, int i3) {
  return {D4{p[i0].x, p[i1].x, p[i2].x, p[i3].x}, D4{p[i0].y, p[i1].y, p[i2].y, p[i3].y},
          D4{p[i0].z, p[i1].z, p[i2].z, p[i3].z}};
}
inline V3<double> lane(const V4& a, int k) { return {a.x[k], a.y[k], a.z[k]}; }
// Four vectors, the k-th in lane k.
inline V4 lanes4(const V3<double> p[4]) { return lanes4(p, 0, 1, 2, 3); }

// a[i][j] <- a[j][i]: moves only.
inline void transpose4(D4 a[4]) {
  const __m256d t0 = _mm256_unpacklo_pd((__m256d)a[0], (__m256d)a[1]);  // a00 a10 a02 a12
  const __m256d t1 = _mm256_unpackhi_pd((__m256d)a[0], (__m256d)a[1]);  // a01 a11 a03 a13
  const __m256d t2 = _mm256_unpacklo_pd((__m256d)a[2], (__m256d)a[3]);  // a20 a30 a22 a32
  const __m256d t3 = _mm256_unpackhi_pd((__m256d)a[2], (__m256d)a[3]);  // a21 a31 a23 a33
  a[0] = (D4)_mm256_permute2f128_pd(t0, t2, 0x20);
  a[1] = (D4)_mm256_permute2f128_pd(t1, t3, 0x20);
  a[2] = (D4)_mm256_permute2f128_pd(t0, t2, 0x31);
  a[3] = (D4)_mm256_permute2f128_pd(t1, t3, 0x31);
}

// Four elements' four 3-vectors each (v[k], lane l element l's) stored
// element after element, 12 doubles each: element l's v[k] at out + 12 l + 3 k.
// Three 4 x 4 transposes in place of 48 single stores.
inline void store_fours12(const V4 v[4], double* out) {
  D4 rows[12];
  for (int k = 0; k < 4; ++k) {
    rows[3 * k] = v[k].x;
    rows[3 * k + 1] = v[k].y;
    rows[3 * k + 2] = v[k].z;
  }
  for (int b = 0; b < 3; ++b) transpose4(rows + 4 * b);
  for (int l = 0; l < 4; ++l)
    for (int b = 0; b < 3; ++b) storeu4(out + 12 * l + 4 * b, rows[4 * b + l]);
}

}  // namespace drape
#else
#define DRAPE_LANES 0
#endif
