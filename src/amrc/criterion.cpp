#include "amrc/criterion.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace drape {

namespace {

// Whether a particle of cell c (closed) has any of `bits` set.
bool any_marked(const Quadtree& t, const Cell& c, const std::vector<uint32_t>* marks, uint32_t bits) {
  if (!marks) return false;
  for (int i = c.i; i <= t.i_end(c); ++i)
    for (int j = c.j; j <= t.j_end(c); ++j)
      if ((*marks)[size_t(i) * t.nj() + j] & bits) return true;
  return false;
}

// The indicator of leaves at `level` in the thresholds' units.
double scale(const Thresholds& th, int level, int max_level) {
  return th.by_width ? std::ldexp(1.0, level - max_level) : 1.0;
}

}  // namespace

uint32_t criterion_bits(double indicator, double speed, const Thresholds& th, int max_level) {
  uint32_t bits = 0;
  for (int l = 0; l <= max_level; ++l) {
    const double v = indicator * scale(th, l, max_level);
    if (v > th.refine) bits |= 1u << l;
    if (v >= th.coarsen) bits |= 1u << (kBlocksMerge + l);
  }
  if (th.coarsen_speed > 0 && speed >= th.coarsen_speed) bits |= kMoving;
  return bits;
}

AdaptStats adapt(Quadtree& tree, const std::vector<uint32_t>& marks, const Thresholds& th,
                 std::vector<Cell>& snapshot, const std::vector<uint32_t>* inside,
                 const std::vector<uint32_t>* near) {
  if (!(th.coarsen < th.refine)) throw std::invalid_argument("amrc: the coarsen threshold must be below refine");
  // A cell's largest indicator counts from 0 (no particle above it): 0 x its
  // scale against the thresholds.
  const bool zero_splits = 0.0 > th.refine, zero_merges = 0.0 < th.coarsen;
  AdaptStats st;
  tree.leaves(snapshot);
  for (const Cell& c : snapshot) {
    const Cell now = tree.leaf_at(c.i, c.j);
    if (!(now == c) || !tree.can_refine(c)) continue;
    const bool bent = zero_splits || any_marked(tree, c, &marks, 1u << c.level);
    const bool in = !bent && any_marked(tree, c, inside, 1u);
    if (bent || in || any_marked(tree, c, near, 1u << c.level)) {
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
  const uint32_t moving = th.coarsen_speed > 0 ? kMoving : 0;
  for (size_t k = 0; k < snapshot.size(); ++k) {
    const Cell c = snapshot[k];
    if (c.level >= tree.max_level()) continue;
    const int l = c.level + 1;
    const Cell parent{(c.i >> l) << l, (c.j >> l) << l, l};
    if (parent.i != c.i || parent.j != c.j) continue;  // visit each parent once, from its first child
    // The children's particles, measured at the children's spacing.
    if (zero_merges && tree.can_coarsen(parent) &&
        !any_marked(tree, parent, &marks, (1u << (kBlocksMerge + c.level)) | moving) &&
        !any_marked(tree, parent, inside, 1u | 1u << l) && !any_marked(tree, parent, near, 1u << (kKeepFine + l)))
      snapshot[merges++] = parent;
  }
  for (size_t k = 0; k < merges; ++k) st.coarsened += tree.coarsen(snapshot[k]) ? 1 : 0;
  return st;
}

AdaptStats adapt(Quadtree& tree, const std::vector<double>& indicator, const Thresholds& th,
                 std::vector<Cell>& scratch, const std::vector<double>* speed,
                 const std::vector<uint32_t>* inside, const std::vector<uint32_t>* near) {
  std::vector<uint32_t> marks(indicator.size());
  for (size_t p = 0; p < indicator.size(); ++p)
    marks[p] = criterion_bits(indicator[p], speed ? (*speed)[p] : 0.0, th, tree.max_level());
  return adapt(tree, marks, th, scratch, inside, near);
}

}  // namespace drape
