#pragma once
// A shear cell read from a state vector: its corners and their positions, as
// the kernel shear_cell (kernels.hpp) takes them.
#include <cstdint>

#include "mesh/cloth.hpp"
#include "solver/kernels.hpp"

namespace drape {

struct CellAt {
  int64_t ids[4];
  V3<double> x[4];
};

// The cell with corners ids (slot, along i, along j, across) at positions z.
inline CellAt cell_at(const int64_t ids[4], const double* z) {
  CellAt a;
  for (int k = 0; k < 4; ++k) {
    a.ids[k] = ids[k];
    a.x[k] = load3<double>(z + 3 * ids[k]);
  }
  return a;
}

inline CellAt cell_at(const Cloth& c, const double* z, int64_t s) {
  int64_t ids[4];
  shear_cell(c, s, ids);
  return cell_at(ids, z);
}

}  // namespace drape
