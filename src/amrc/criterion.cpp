#include "amrc/criterion.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace drape {

namespace {

double largest(const Quadtree& t, const Cell& c, const std::vector<double>& indicator) {
  double m = 0;
  for (int i = c.i; i <= t.i_end(c); ++i)
    for (int j = c.j; j <= t.j_end(c); ++j) m = std::max(m, indicator[size_t(i) * t.nj() + j]);
  return m;
}

// Whether a particle of cell c (closed) has any of `bits` in its inside mask.
bool any_inside(const Quadtree& t, const Cell& c, const std::vector<double>* inside, unsigned bits) {
  if (!inside) return false;
  for (int i = c.i; i <= t.i_end(c); ++i)
    for (int j = c.j; j <= t.j_end(c); ++j)
      if (unsigned((*inside)[size_t(i) * t.nj() + j]) & bits) return true;
  return false;
}

}  // namespace

AdaptStats adapt(Quadtree& tree, const std::vector<double>& indicator, const Thresholds& th,
                 std::vector<Cell>& snapshot, const std::vector<double>* speed,
                 const std::vector<double>* inside, const std::vector<double>* near) {
  if (!(th.coarsen < th.refine)) throw std::invalid_argument("amrc: the coarsen threshold must be below refine");
  // The indicator of leaves at `level` in the thresholds' units.
  auto scale = [&](int level) { return th.by_width ? std::ldexp(1.0, level - tree.max_level()) : 1.0; };
  AdaptStats st;
  tree.leaves(snapshot);
  for (const Cell& c : snapshot) {
    const Cell now = tree.leaf_at(c.i, c.j);
    if (!(now == c) || !tree.can_refine(c)) continue;
    const bool bent = largest(tree, c, indicator) * scale(c.level) > th.refine;
    const bool in = !bent && any_inside(tree, c, inside, 1u);
    if (bent || in || any_inside(tree, c, near, 1u << c.level)) {
      tree.refine(c);
      ++st.refined;
      st.refined_inside += in ? 1 : 0;
      st.refined_near += bent || in ? 0 : 1;
    }
  }
  // Merges are judged on the tree as this sweep found it, then made: made one
  // by one, a merge could unblock a neighbour's later in the same sweep but
  // not an earlier one's, so the mesh (and a symmetric drape) would follow the
  // sweep's order. Merges judged together never block one another (each makes
  // cells coarser only), so each still holds when it is made.
  tree.leaves(snapshot);
  size_t merges = 0;  // the parents to merge, written over the front of snapshot
  for (size_t k = 0; k < snapshot.size(); ++k) {
    const Cell c = snapshot[k];
    if (c.level >= tree.max_level()) continue;
    const int l = c.level + 1;
    const Cell parent{(c.i >> l) << l, (c.j >> l) << l, l};
    if (parent.i != c.i || parent.j != c.j) continue;  // visit each parent once, from its first child
    // The children's particles, measured at the children's spacing.
    if (tree.can_coarsen(parent) && largest(tree, parent, indicator) * scale(c.level) < th.coarsen &&
        (!speed || largest(tree, parent, *speed) < th.coarsen_speed) && !any_inside(tree, parent, inside, 1u | 1u << l) && !any_inside(tree, parent, near, 1u << (kKeepFine + l)))
      snapshot[merges++] = parent;
  }
  for (size_t k = 0; k < merges; ++k) st.coarsened += tree.coarsen(snapshot[k]) ? 1 : 0;
  return st;
}

}  // namespace drape
