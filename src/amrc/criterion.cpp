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

}  // namespace

AdaptStats adapt(Quadtree& tree, const std::vector<double>& indicator, const Thresholds& th,
                 std::vector<Cell>& snapshot, const std::vector<double>* speed) {
  if (!(th.coarsen < th.refine)) throw std::invalid_argument("amrc: the coarsen threshold must be below refine");
  // The indicator of leaves at `level` in the thresholds' units.
  auto scale = [&](int level) { return th.by_width ? std::ldexp(1.0, level - tree.max_level()) : 1.0; };
  AdaptStats st;
  tree.leaves(snapshot);
  for (const Cell& c : snapshot) {
    const Cell now = tree.leaf_at(c.i, c.j);
    if (now == c && tree.can_refine(c) && largest(tree, c, indicator) * scale(c.level) > th.refine) {
      tree.refine(c);
      ++st.refined;
    }
  }
  tree.leaves(snapshot);
  for (const Cell& c : snapshot) {
    if (c.level >= tree.max_level()) continue;
    const int l = c.level + 1;
    const Cell parent{(c.i >> l) << l, (c.j >> l) << l, l};
    if (parent.i != c.i || parent.j != c.j) continue;  // visit each parent once, from its first child
    // The children's particles, measured at the children's spacing.
    if (tree.can_coarsen(parent) && largest(tree, parent, indicator) * scale(c.level) < th.coarsen &&
        (!speed || largest(tree, parent, *speed) < th.coarsen_speed)) {
      tree.coarsen(parent);
      ++st.coarsened;
    }
  }
  return st;
}

}  // namespace drape
