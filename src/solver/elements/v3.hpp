#pragma once
// Three-vectors for the element kernels, templated on the scalar (double, or
// Dual for the reference Hessian-vector products).
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
// A constant as the scalar T (lanes.hpp: in every lane), so that one kernel
// text serves double, Dual and four-lane vectors alike.
template <class T>
inline T num(double a) { return T(a); }
// Square root of the scalar T (lanes.hpp: lane by lane).
template <class T>
inline T root(T a) {
  using std::sqrt;
  return sqrt(a);
}
template <class T>
inline V3<T> load3(const double* p) { return {T(p[0]), T(p[1]), T(p[2])}; }
inline V3<Dual> load3(const double* p, const double* v) {
  return {Dual(p[0], v[0]), Dual(p[1], v[1]), Dual(p[2], v[2])};
}
template <class T>
inline void store3(const V3<T>& a, T* out) { out[0] = a.x; out[1] = a.y; out[2] = a.z; }

}  // namespace drape
