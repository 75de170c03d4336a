#include "solver/memory_table.hpp"

#include <algorithm>

#include "mesh/active_lists.hpp"
#include "mesh/cloth.hpp"

namespace drape {

namespace {

template <class T>
size_t cap(const std::vector<T>& v) {
  return v.capacity() * sizeof(T);
}

size_t list_bytes(const ActiveList& l) { return cap(l.items) + cap(l.tile_begin); }

size_t runs_bytes(const IndexRuns& r) { return cap(r.bounds) + cap(r.tile_begin); }

}  // namespace

void add_memory(MemoryTable& t, const Cloth& c) {
  const char* o = "Cloth";
  // z's positions follow the grid; its forces the slots (Layout).
  const size_t forces = size_t(c.z.size() - std::min(c.z.size(), size_t(3 * c.layout.n))) * sizeof(double);
  t.add(o, "z's positions", cap(c.z) - forces);
  t.add(o, "z's forces", forces);
  t.add(o, "x1, x2 (earlier positions)", cap(c.x1) + cap(c.x2));
  t.add(o, "slots of x1, x2, the forces, masses, neighbours and cells (several ranks)", c.slot_of);
  t.add(o, "mass", cap(c.mass));
  t.add(o, "flags, level", cap(c.flags) + cap(c.level));
  t.add(o, "next, prev (neighbour tables)", cap(c.next[0]) + cap(c.next[1]) + cap(c.prev[0]) + cap(c.prev[1]));
  t.add(o, "element switches", cap(c.edge_on) + cap(c.triple_on) + cap(c.shear_on));
  size_t cells = 0;
  for (int k = 0; k < 3; ++k) cells += cap(c.cell[k]) + cap(c.corner_of[k]);
  t.add(o, "cell, corner_of (shear cells' corners)", cells);
}

void add_memory(MemoryTable& t, const ActiveLists& l) {
  const char* o = "ActiveLists";
  t.add(o, "particles, edges, triples, cells (and the ring's)",
        list_bytes(l.particles) + list_bytes(l.edges) + list_bytes(l.triples) + list_bytes(l.shears) +
            list_bytes(l.ring_edges) + list_bytes(l.ring_triples) + list_bytes(l.ring_shears));
  t.add(o, "unknowns' runs", runs_bytes(l.unknowns) + runs_bytes(l.unknown_spans));
  t.add(o, "hanging links", l.hanging);
}

}  // namespace drape
