#pragma once
// A quadtree's mesh on the cloth: particle marks and levels, edges and
// triples along leaf sides, rest geometry, masses from the leaves (the total
// is the finest mesh's), and the hanging particles' links for the solver.
#include <vector>

#include "mesh/active_lists.hpp"
#include "mesh/quadtree.hpp"

namespace drape {

void apply_tree(const Quadtree& tree, Cloth& c, double density, bool shear_enabled);
void hanging_links(const Quadtree& tree, std::vector<HangingLink>& out);

}  // namespace drape
