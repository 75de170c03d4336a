#pragma once
// Forward-mode dual numbers: evaluating an element's gradient formula at
// x + eps*v yields, in the eps part, the exact Hessian-vector product H*v.
// The Newton cost needs H*R (R: residuals of the element's particles); this
// gives it without writing out the bending and shear Hessians by hand.
#include <cmath>

namespace drape {

struct Dual {
  double v = 0, d = 0;
  Dual() = default;
  Dual(double value, double deriv = 0) : v(value), d(deriv) {}
};

inline Dual operator+(Dual a, Dual b) { return {a.v + b.v, a.d + b.d}; }
inline Dual operator-(Dual a, Dual b) { return {a.v - b.v, a.d - b.d}; }
inline Dual operator-(Dual a) { return {-a.v, -a.d}; }
inline Dual operator*(Dual a, Dual b) { return {a.v * b.v, a.d * b.v + a.v * b.d}; }
inline Dual operator/(Dual a, Dual b) {
  return {a.v / b.v, (a.d * b.v - a.v * b.d) / (b.v * b.v)};
}
inline Dual sqrt(Dual a) {
  const double s = std::sqrt(a.v);
  return {s, a.d / (2 * s)};
}
inline Dual atan2(Dual y, Dual x) {
  return {std::atan2(y.v, x.v), (x.v * y.d - y.v * x.d) / (x.v * x.v + y.v * y.v)};
}
inline double value(Dual a) { return a.v; }
inline double value(double a) { return a; }

}  // namespace drape
