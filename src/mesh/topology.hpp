#pragma once
// The active mesh's topology and geometry from the particles' flags (and
// the quadtree's leaves, with AMRC).
#include "mesh/cloth.hpp"

namespace drape {

class Quadtree;

// Rebuilds next/prev neighbour tables and element switches from particle
// flags: an edge joins consecutive active particles on a grid line, a triple
// sits at an active particle with active neighbours on both sides, a shear
// corner at an active particle with both a warp and a weft neighbour.
// With a quadtree, only along leaf sides (never across a coarse leaf).
void rebuild_topology(Cloth& c, bool shear_enabled, const Quadtree* tree = nullptr);

// Rest lengths, widths, areas and particle masses (density * represented
// area) from the neighbour tables; the total mass is the finest mesh's.
void rebuild_geometry(Cloth& c, double density);
}  // namespace drape
