#pragma once
// A particle's shear cross read from a state vector: its particles, the arms
// present and their positions, as the kernel shear_cross (kernels.hpp) takes them.
#include <cstdint>

#include "solver/cloth.hpp"
#include "solver/kernels.hpp"

namespace drape {

struct CrossAt {
  int64_t ids[5];
  unsigned arms;
  V3<double> x[5];
};

inline CrossAt cross_at(const Cloth& c, const double* z, int64_t s) {
  CrossAt a;
  a.arms = shear_arms(c, s, a.ids);
  for (int k = 0; k < 5; ++k) a.x[k] = load3<double>(z + 3 * a.ids[k]);
  return a;
}

}  // namespace drape
