#include "amrc/remesh.hpp"
#include "mesh/topology.hpp"

namespace drape {

void apply_tree(const Quadtree& tree, Cloth& c, double density, bool shear_enabled) {
  tree.mark(c.flags, c.level);
  rebuild_topology(c, shear_enabled, &tree);
  rebuild_geometry(c, density);
  tree.masses(density, c.grid.hi, c.grid.hj, c.slots(), c.mass);
}

void hanging_links(const Quadtree& tree, std::vector<HangingLink>& out) {
  out.clear();
  for (const Quadtree::Hanging& g : tree.hanging()) out.push_back({g.h, g.a, g.b, g.t});
}

}  // namespace drape
