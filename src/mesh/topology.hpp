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

// Particle masses (density * represented area) from the neighbour tables;
// the total mass is the finest mesh's.
void rebuild_geometry(Cloth& c, double density);

// An element's rest geometry on the active mesh, from the neighbour tables
// (the evaluator lays it out in list order for its own elements; nothing
// holds it by slot): an edge's rest length and the width of cloth it stands
// for, a triple's rest length (its particle's extent along the line) and
// width, a cell's area. Slot s must be on.
struct RestGeometry {
  double rest, width;
};
RestGeometry edge_rest_geometry(const Cloth& c, int64_t s);
RestGeometry triple_rest_geometry(const Cloth& c, int64_t s);
double cell_area(const Cloth& c, int64_t s);
}  // namespace drape
