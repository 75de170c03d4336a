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

}  // namespace drape
