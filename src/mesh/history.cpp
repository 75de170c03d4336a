// A rank's step history (x1, x2), element forces and the tables beside them
// for the particles it holds only.
#include <algorithm>
#include <limits>
#include <stdexcept>
#include <utility>

#include "mesh/cloth.hpp"

namespace drape {

std::vector<int64_t> held_particles(const Cloth& c) {
  std::vector<int64_t> held;
  for (int64_t p = 0; p < c.grid.n(); ++p)
    if (c.holds(p)) held.push_back(p);
  return held;
}

namespace {
template <class... V>
void release(V&... v) {
  (std::vector<typename V::value_type>().swap(v), ...);
}

// z's force blocks for the slots `slot` (m of them), carried from c's.
std::vector<double> held_z(const Cloth& c, const std::vector<int32_t>& slot, const std::vector<int64_t>& held) {
  Layout L{c.layout.n, int64_t(held.size())};
  std::vector<double> z(size_t(L.size()), 0.0);
  std::copy(c.z.begin(), c.z.begin() + 3 * c.layout.n, z.begin());
  for (int64_t p : held) {
    if (!c.holds(p)) continue;
    const int64_t q = slot[size_t(p)];
    for (int b = 0; b < 3; ++b)
      for (int64_t s = b < 2 ? 2 * p : p, e = b < 2 ? 2 * p + 2 : p + 1; s < e; ++s)
        z[size_t(L.force(b, s, q))] = c.force(b, s);
  }
  return z;
}
// The cells' corner tables and the neighbour tables for the slots `slot`,
// carried from c's.
void hold_tables(Cloth& c, const std::vector<int32_t>& slot, const std::vector<int64_t>& held) {
  auto carry = [&](std::vector<int32_t>* tables, int count) {
    for (int k = 0; k < count; ++k) {
      std::vector<int32_t> out(held.size(), -1);
      for (int64_t p : held)
        if (c.holds(p)) out[size_t(slot[size_t(p)])] = tables[k][size_t(c.slot(p))];
      tables[k].swap(out);
    }
  };
  carry(c.cell, 3);
  carry(c.corner_of, 3);
  carry(c.next, 2);
  carry(c.prev, 2);
}

// The element switches for the slots `slot`, carried from c's (`per` a
// particle: 2 edges or triples, 1 cell).
void hold_switches(const Cloth& c, std::vector<uint8_t>& on, int per, const std::vector<int32_t>& slot,
                   const std::vector<int64_t>& held) {
  std::vector<uint8_t> out(per * held.size(), 0);
  for (int64_t p : held)
    if (c.holds(p))
      for (int k = 0; k < per; ++k) out[size_t(per * slot[size_t(p)] + k)] = on[size_t(per * c.slot(p) + k)];
  on.swap(out);
}
}  // namespace

namespace {
void check_slots(const std::vector<int64_t>& held) {
  if (held.size() > size_t(std::numeric_limits<int32_t>::max() / 3))
    throw std::length_error("hold_particles: more particles than 32-bit slots reach");
}
}  // namespace

int64_t hold_slots(Cloth& c, const std::vector<int64_t>& held) {
  check_slots(held);
  c.slot_of.assign(size_t(c.grid.n()), -1);
  for (size_t s = 0; s < held.size(); ++s) c.slot_of[size_t(held[s])] = int32_t(s);
  ++c.held_version;
  return int64_t(held.size());
}

void hold_particles(Cloth& c, const std::vector<int64_t>& held) {
  check_slots(held);
  std::vector<int32_t> slot(size_t(c.grid.n()), -1);
  std::vector<double> x1(3 * held.size(), 0.0), x2(3 * held.size(), 0.0), mass(held.size(), 0.0);
  for (size_t s = 0; s < held.size(); ++s) {
    const int64_t p = held[s];
    slot[size_t(p)] = int32_t(s);
    if (!c.holds(p)) continue;
    mass[s] = c.mass_at(p);
    for (int k = 0; k < 3; ++k) {
      x1[3 * s + k] = c.x1_at(p)[k];
      x2[3 * s + k] = c.x2_at(p)[k];
    }
  }
  // Each old array goes as soon as its new one is full, before the next is
  // made: at the first hold (the whole grid's arrays) the peak stays that
  // of the grid's cloth. x1, x2 and the masses are not read below.
  c.x1.swap(x1);
  c.x2.swap(x2);
  c.mass.swap(mass);
  release(x1, x2, mass);
  hold_tables(c, slot, held);
  hold_switches(c, c.edge_on, 2, slot, held);
  hold_switches(c, c.triple_on, 2, slot, held);
  hold_switches(c, c.shear_on, 1, slot, held);
  std::vector<double> z = held_z(c, slot, held);
  c.z.swap(z);
  release(z);
  c.slot_of.swap(slot);
  c.layout.m = int64_t(held.size());
  ++c.held_version;
}

}  // namespace drape

namespace drape {

std::vector<int64_t> with_tiles(std::vector<int64_t> held, const Tiling& tl, const std::vector<int>& tiles) {
  for (int t : tiles) {
    const TileRange r = tl.range(t);
    for (int i = r.i0; i < r.i1; ++i)
      for (int j = r.j0; j < r.j1; ++j) held.push_back(int64_t(i) * tl.nj + j);
  }
  std::sort(held.begin(), held.end());
  held.erase(std::unique(held.begin(), held.end()), held.end());
  return held;
}

void hold_with_tiles(Cloth& c, std::vector<int64_t> held, const Tiling& tl, const std::vector<int>& tiles) {
  hold_particles(c, with_tiles(std::move(held), tl, tiles));
}

}  // namespace drape
