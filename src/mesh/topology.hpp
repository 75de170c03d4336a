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

// Half the rest distance from particle a to particle b (b after a) along d,
// in units of the spacing: extents and rest lengths add these.
inline double half_gap(const Grid& g, int d, int64_t a, int64_t b) { return 0.5 * double(b - a) / g.stride(d); }
// A triple's rest length from its particle p and its neighbours prev and
// next along d alone (the same arithmetic as triple_rest_geometry's): the
// evaluator recomputes it from the neighbours it holds instead of keeping it.
inline double triple_rest_length(const Grid& g, int d, int64_t prev, int64_t p, int64_t next) {
  return (half_gap(g, d, p, next) + half_gap(g, d, prev, p)) * g.h(d);
}
// A cell's area from its slot s and its corners 0 (along i) and 1 (along j).
inline double cell_area(const Grid& g, int64_t s, int64_t corner0, int64_t corner1) {
  return double(corner0 - s) / g.nj * g.hi * double(corner1 - s) * g.hj;
}
}  // namespace drape
