// Coarsening: the children of a cell merge back into it.
#include "mesh/quadtree.hpp"

namespace drape {

bool Quadtree::can_coarsen(const Cell& parent) const {
  const int l = parent.level;
  if (l < 1 || l > max_level_ || !on_grid(parent.i, parent.j)) return false;
  if ((parent.i & ((1 << l) - 1)) || (parent.j & ((1 << l) - 1))) return false;  // not aligned
  // Every finest interval inside at the children's level: they are leaves.
  for (int ci = parent.i; ci < i_end(parent); ++ci)
    for (int cj = parent.j; cj < j_end(parent); ++cj)
      if (leaf_at(ci, cj).level != l - 1) return false;
  // No neighbour finer than the children, or it would end two levels finer.
  bool ok = true;
  each_outside_neighbour(parent, [&](int ci, int cj) { ok = ok && leaf_at(ci, cj).level >= l - 1; });
  return ok;
}

bool Quadtree::coarsen(const Cell& parent) {
  if (!can_coarsen(parent)) return false;
  set_level(parent, parent.level);
  return true;
}

}  // namespace drape
