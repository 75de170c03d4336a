// Refinement: a leaf splits into its (up to four, clipped) children.
#include "mesh/quadtree.hpp"

namespace drape {

void Quadtree::refine(const Cell& leaf) {
  if (!can_refine(leaf) || !is_leaf(leaf)) return;
  // A neighbour coarser than this leaf would end two levels coarser than its
  // children: refine it first (which may cascade further out).
  for (bool again = true; again;) {
    again = false;
    each_outside_neighbour(leaf, [&](int ci, int cj) {
      if (again) return;
      const Cell n = leaf_at(ci, cj);
      if (n.level > leaf.level) {
        refine(n);
        again = true;  // the neighbourhood changed: look again
      }
    });
  }
  set_level(leaf, leaf.level - 1);
}

}  // namespace drape
