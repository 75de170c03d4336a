#include "mesh/topology.hpp"

#include <algorithm>
#include <cmath>

#include "mesh/quadtree.hpp"

namespace drape {

namespace {
// Shear cells: the leaves, each on the slot of its lower corner. Without a
// tree, the finest cells whose four sides are mesh edges.
void rebuild_cells(Cloth& c, bool shear_enabled, const Quadtree* tree) {
  const Grid& g = c.grid;
  for (int k = 0; k < 3; ++k) {  // the held particles' (same sizes between holds: no allocation)
    c.cell[k].assign(size_t(c.layout.m), -1);
    c.corner_of[k].assign(size_t(c.layout.m), -1);
  }
  c.shear_on.assign(size_t(c.layout.m), 0);
  if (!shear_enabled) return;
  auto put = [&](int64_t s, int64_t a, int64_t b, int64_t d) {
    if (c.holds(s)) c.shear_on[size_t(c.slot(s))] = 1;
    const int64_t corner[3] = {a, b, d};
    for (int k = 0; k < 3; ++k) {
      if (c.holds(s)) c.cell[k][size_t(c.slot(s))] = int32_t(corner[k]);
      if (c.holds(corner[k])) c.corner_of[k][size_t(c.slot(corner[k]))] = int32_t(s);
    }
  };
  if (tree) {
    tree->for_each_leaf([&](const Cell& l) {
      const int ie = tree->i_end(l), je = tree->j_end(l);
      put(g.id(l.i, l.j), g.id(ie, l.j), g.id(l.i, je), g.id(ie, je));
    });
    return;
  }
  // Without a tree an edge joins neighbouring active particles: the cell
  // is there where its four corners are active.
  for (int i = 0; i + 1 < g.ni; ++i)
    for (int j = 0; j + 1 < g.nj; ++j) {
      const int64_t s = g.id(i, j);
      if (c.active(s) && c.active(s + g.nj) && c.active(s + 1) && c.active(s + g.nj + 1)) put(s, s + g.nj, s + 1, s + g.nj + 1);
    }
}
}  // namespace

void rebuild_topology(Cloth& c, bool shear_enabled, const Quadtree* tree) {
  const Grid& g = c.grid;
  for (int d = 0; d < 2; ++d) {  // the held particles' (same sizes between holds: no allocation)
    c.next[d].assign(size_t(c.layout.m), -1);
    c.prev[d].assign(size_t(c.layout.m), -1);
  }
  c.edge_on.assign(size_t(2 * c.layout.m), 0);
  c.triple_on.assign(size_t(2 * c.layout.m), 0);
  // Walk each grid line linking consecutive active particles: an edge from
  // each linked particle, a triple at each linked both ways.
  auto walk = [&](int d, int64_t first, int count) {
    int64_t last = -1;
    bool last_in = false;  // whether `last` has a link in
    for (int k = 0; k < count; ++k) {
      const int64_t p = first + k * g.stride(d);
      if (!c.active(p)) continue;
      const bool in = last >= 0 && (!tree || tree->on_side(last, p));
      if (in) {
        if (c.holds(last)) {
          c.next[d][size_t(c.slot(last))] = int32_t(p);
          c.edge_on[size_t(c.pair_slot(2 * last + d))] = 1;
          if (last_in) c.triple_on[size_t(c.pair_slot(2 * last + d))] = 1;
        }
        if (c.holds(p)) c.prev[d][size_t(c.slot(p))] = int32_t(last);
      }
      last = p;
      last_in = in;
    }
  };
  for (int i = 0; i < g.ni; ++i) walk(1, g.id(i, 0), g.nj);
  for (int j = 0; j < g.nj; ++j) walk(0, g.id(0, j), g.ni);
  rebuild_cells(c, shear_enabled, tree);
}


namespace {
// Half the rest distance to each active neighbour along d: the extent of cloth a particle stands for.
double extent(const Cloth& c, int64_t p, int d) {
  double e = 0;
  const int64_t nx = c.next_at(d, p), pv = c.prev_at(d, p);
  if (nx >= 0) e += half_gap(c.grid, d, p, nx);
  if (pv >= 0) e += half_gap(c.grid, d, pv, p);
  return e * c.grid.h(d);
}

// Whether a particle of the 3 x 3 block about p is removed (a disc's outline).
bool near_removed(const Cloth& c, int64_t p) {
  const Grid& g = c.grid;
  const int i = g.i_of(p), j = g.j_of(p);
  for (int a = std::max(i - 1, 0); a <= std::min(i + 1, g.ni - 1); ++a)
    for (int b = std::max(j - 1, 0); b <= std::min(j + 1, g.nj - 1); ++b)
      if (c.flags[g.id(a, b)] & kRemoved) return true;
  return false;
}

// The area p stands for on a cut outline: a quarter of each cell it is a
// corner of (a cell whose four corners are active). Extents would count a
// missing diagonal cell at a concave corner of the staircase.
double cell_quarters(const Cloth& c, int64_t p) {
  const Grid& g = c.grid;
  const int i = g.i_of(p), j = g.j_of(p);
  double area = 0;
  for (int a = i - 1; a <= i; ++a)
    for (int b = j - 1; b <= j; ++b) {
      if (a < 0 || b < 0 || a + 1 >= g.ni || b + 1 >= g.nj) continue;
      bool whole = true;
      for (int64_t q : {g.id(a, b), g.id(a + 1, b), g.id(a, b + 1), g.id(a + 1, b + 1)}) whole = whole && c.active(q);
      if (whole) area += 0.25 * g.hi * g.hj;
    }
  return area;
}
}  // namespace

void rebuild_geometry(Cloth& c, double density) {
  const int64_t n = c.grid.n();
#pragma omp parallel for schedule(static)
  for (int64_t p = 0; p < n; ++p) {
    if (!c.holds(p)) continue;
    const double ext[2] = {c.active(p) ? extent(c, p, 0) : 0, c.active(p) ? extent(c, p, 1) : 0};
    c.mass_at(p) = c.active(p) && near_removed(c, p) ? density * cell_quarters(c, p) : density * ext[0] * ext[1];
  }
}

RestGeometry edge_rest_geometry(const Cloth& c, int64_t s) {
  const int64_t p = s >> 1, q = c.next_at(s & 1, p);
  const int d = int(s & 1);
  const double len = double(q - p) / c.grid.stride(d) * c.grid.h(d);
  return {len, 0.5 * (extent(c, p, 1 - d) + extent(c, q, 1 - d))};
}

RestGeometry triple_rest_geometry(const Cloth& c, int64_t s) {
  const int d = int(s & 1);
  return {extent(c, s >> 1, d), extent(c, s >> 1, 1 - d)};
}

// A cell stands for its own area.
double cell_area(const Cloth& c, int64_t s) {
  return cell_area(c.grid, s, c.cell_at(0, s), c.cell_at(1, s));
}

}  // namespace drape
