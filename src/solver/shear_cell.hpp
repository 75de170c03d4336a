#pragma once
// A shear cell read from a state vector: its corners and their positions, as
// the kernel shear_cell (kernels.hpp) takes them.
#include <cstdint>

#include "solver/cloth.hpp"
#include "solver/kernels.hpp"

namespace drape {

struct CellAt {
  int64_t ids[4];
  V3<double> x[4];
};

inline CellAt cell_at(const Cloth& c, const double* z, int64_t s) {
  CellAt a;
  shear_cell(c, s, a.ids);
  for (int k = 0; k < 4; ++k) a.x[k] = load3<double>(z + 3 * a.ids[k]);
  return a;
}

}  // namespace drape
