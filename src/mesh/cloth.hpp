#pragma once
// The cloth laid out on the finest grid, once, for the whole run (docs/design.md §2):
// particle p = i*NJ + j; element slots hang off their first particle:
//   edge   slot 2p+d: p -> next particle along direction d (0 warp/i, 1 weft/j)
//   triple slot 2p+d: prev -> p -> next along d (bending at p)
//   shear  slot p   : the cell (a leaf of the active mesh) whose lower corner is p
// AMRC switches slots on and off; nothing is reallocated during a run.
//
// The unknowns live in one vector z = [x (3N) | tension (2M) | moment (2M) |
// shear (M)] so the minimizer works on a single array: positions at grid
// ids, element forces at their first particle's slot (Cloth::slot; M = N
// on one rank, the rank's tiles' and ghosts' particles on several).
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "mesh/tiles.hpp"

namespace drape {

enum ParticleFlag : uint8_t {
  kActive = 1,   // part of the active mesh
  kFixed = 2,    // position prescribed (clamped), not an unknown
  kHanging = 4,  // AMRC hanging particle: interpolated, not solved for
  kRemoved = 8,  // outside the specimen (cloth.shape = "disc"): never active, no element touches it
};

struct Grid {
  int ni = 0, nj = 0;  // particles along i (warp) and j (weft)
  double hi = 0, hj = 0;  // rest spacing along i and j, m
  int64_t n() const { return int64_t(ni) * nj; }
  int64_t id(int i, int j) const { return int64_t(i) * nj + j; }
  int i_of(int64_t p) const { return int(p / nj); }
  int j_of(int64_t p) const { return int(p % nj); }
  double h(int d) const { return d == 0 ? hi : hj; }
  // Step in p along direction d.
  int64_t stride(int d) const { return d == 0 ? nj : 1; }
};

// The evaluator's per-element buffers, in doubles an element: it writes its
// contribution to each of its particles there (3 doubles a particle).
constexpr int kEdgeSlot = 6, kTripleSlot = 9, kShearSlot = 12;
// The most particles a cloth may have: GatherRow's int32 offsets must reach
// the end of the triple buffer (2 triples a particle).
constexpr int64_t kMaxParticles = INT32_MAX / (2 * kTripleSlot);

// Where one particle's contributions lie in those buffers, in the gather's
// fixed order (cost.hpp): per direction d, the edge from it, the edge into
// it, then the triples centred at its next, at itself and at its previous
// particle; then the cell it is the lower corner of, and the cells it is
// corner 1, 2, 3 of. -1 where there is no such element. 64 bytes: one cache
// line where the neighbour tables and switches took about ten.
struct alignas(64) GatherRow {
  static constexpr int kPerDirection = 5, kShear = 10;
  int32_t at[16];
};

// Offsets of the unknown blocks in z: n grid particles' positions, then
// the forces of m slots' elements (2 edges, 2 triples and a cell a slot).
struct Layout {
  int64_t n = 0, m = 0;
  int64_t x() const { return 0; }
  int64_t tension() const { return 3 * n; }
  int64_t moment() const { return 3 * n + 2 * m; }
  int64_t shear() const { return 3 * n + 4 * m; }
  int64_t size() const { return 3 * n + 5 * m; }
  // Where force block b (0 tension, 1 moment, 2 shear) starts.
  int64_t block(int b) const { return b == 0 ? tension() : b == 1 ? moment() : shear(); }
  // z's index of the force of element slot s (2p+d, or p for a cell) of
  // block b, its particle p at slot q.
  int64_t force(int b, int64_t s, int64_t q) const { return b < 2 ? block(b) + 2 * q + (s & 1) : block(b) + q; }
};

struct Cloth {
  Grid grid;
  Layout layout;
  std::vector<double> z;         // unknowns (see Layout)
  // Positions at the start of this step and the one before, 3 values for
  // each particle this rank holds (its tiles' and its ghosts'), at slot(p):
  // on several ranks not sized by the grid (hold_particles), nor are z's
  // force blocks.
  std::vector<double> x1, x2;
  // Each particle's slot in x1, x2 and z's force blocks (-1: not held
  // here); empty: every particle, at its grid id. `held_version` changes
  // with it.
  std::vector<int32_t> slot_of;
  uint64_t held_version = 0;
  // kg per particle (density * area it represents), held in slots like x1:
  // read through mass_at.
  std::vector<double> mass;
  std::vector<uint8_t> flags;    // ParticleFlag per particle
  std::vector<uint8_t> level;    // AMRC level of the particle's finest leaf (0: finest)
  // Neighbour tables over the active mesh: next/prev active particle along d, -1 at a border.
  // 32-bit like GatherRow's offsets (kMaxParticles is far below INT32_MAX).
  // Held in slots like x1: read through next_at, prev_at.
  std::vector<int32_t> next[2], prev[2];
  // Element slot switches (1 = active element), held in slots like x1
  // (an edge's and a triple's at 2 slot(p) + d, a cell's at slot(p)): read
  // through edge_on_at, triple_on_at, shear_on_at.
  std::vector<uint8_t> edge_on, triple_on, shear_on;
  // Shear cells: cell[k] holds corner k+1 of slot s's cell (k = 0: along i
  // from s, 1: along j, 2: across), -1 where the slot is off; corner_of[k]
  // the slot whose corner k+1 p is (at most one: the leaves tile the
  // cloth). Held in slots like x1 (several ranks: the rank's tiles' and
  // ghosts' particles): read through cell_at and corner_at.
  std::vector<int32_t> cell[3], corner_of[3];
  // The elements' rest geometry is not held here: the evaluator keeps its
  // own elements' in list order (mesh/topology.hpp computes it).
  double time = 0, dt = 1e-3, dt_prev = 1e-3;
  int step = 0;

  double* x() { return z.data(); }
  const double* x() const { return z.data(); }
  double* tension() { return z.data() + layout.tension(); }
  const double* tension() const { return z.data() + layout.tension(); }
  double* moment() { return z.data() + layout.moment(); }
  const double* moment() const { return z.data() + layout.moment(); }
  double* shear() { return z.data() + layout.shear(); }
  const double* shear() const { return z.data() + layout.shear(); }

  int64_t slot(int64_t p) const { return slot_of.empty() ? p : int64_t(slot_of[p]); }
  bool holds(int64_t p) const { return slot_of.empty() || slot_of[p] >= 0; }
  // The slot map for kernels that take one (null: the grid ids).
  const int32_t* slots() const { return slot_of.empty() ? nullptr : slot_of.data(); }
  double* x1_at(int64_t p) { return &x1[size_t(3 * slot(p))]; }
  const double* x1_at(int64_t p) const { return &x1[size_t(3 * slot(p))]; }
  double* x2_at(int64_t p) { return &x2[size_t(3 * slot(p))]; }
  const double* x2_at(int64_t p) const { return &x2[size_t(3 * slot(p))]; }
  int64_t next_at(int d, int64_t p) const { return next[d][size_t(slot(p))]; }
  int64_t prev_at(int d, int64_t p) const { return prev[d][size_t(slot(p))]; }
  double& mass_at(int64_t p) { return mass[size_t(slot(p))]; }
  double mass_at(int64_t p) const { return mass[size_t(slot(p))]; }
  // Whether element s (edge, triple: 2p+d; cell: p) is on; false where p
  // is not held here (its switches are its holders').
  bool edge_on_at(int64_t s) const { return holds(s >> 1) && edge_on[size_t(pair_slot(s))]; }
  bool triple_on_at(int64_t s) const { return holds(s >> 1) && triple_on[size_t(pair_slot(s))]; }
  bool shear_on_at(int64_t s) const { return holds(s) && shear_on[size_t(slot(s))]; }
  // Where element slot s = 2p+d of a held p lies in the arrays of two a particle.
  int64_t pair_slot(int64_t s) const { return 2 * slot(s >> 1) + (s & 1); }
  // Corner k+1 of the cell at slot s (held); the cell p is corner k+1 of
  // (-1: none, or p not held here).
  int64_t cell_at(int k, int64_t s) const { return cell[k][size_t(slot(s))]; }
  int64_t corner_at(int k, int64_t p) const { return holds(p) ? int64_t(corner_of[k][size_t(slot(p))]) : -1; }
  // z's index of element slot s's force in block b (0 tension, 1 moment,
  // 2 shear: Layout::force); its particle must be held.
  int64_t force_index(int b, int64_t s) const { return layout.force(b, s, slot(b < 2 ? s >> 1 : s)); }
  double& force(int b, int64_t s) { return z[size_t(force_index(b, s))]; }
  double force(int b, int64_t s) const { return z[size_t(force_index(b, s))]; }

  bool active(int64_t p) const { return flags[p] & kActive; }
  bool free(int64_t p) const { return (flags[p] & (kActive | kFixed | kHanging)) == kActive; }
  // The held particles' mass: the whole cloth's on one rank only (several
  // ranks: total_mass in solver/model.hpp).
  double total_mass() const;
};

// A shear cell at slot s: ids = [s, along i, along j, across] (on slots only).
inline void shear_cell(const Cloth& c, int64_t s, int64_t ids[4]) {
  ids[0] = s;
  for (int k = 0; k < 3; ++k) ids[k + 1] = c.cell_at(k, s);
}

// Particle p's index in an array held in slots (Cloth::slots; null: p).
inline int64_t slot_in(const int32_t* slot, int64_t p) { return slot ? int64_t(slot[p]) : p; }

// x1, x2, z's forces, the masses, the neighbour tables, the cells' corners
// and the element switches for the particles `held`
// (ascending grid ids) only, in that order: values of particles held before
// carried over, the others 0 (-1 for the corners, switches off: rebuild_topology then).
void hold_particles(Cloth& c, const std::vector<int64_t>& held);
// The slot map of a cloth made in slots (make_cloth): the particles `held`
// (ascending grid ids) at slots 0, 1, ...; returns their count. The arrays
// are the caller's to size.
int64_t hold_slots(Cloth& c, const std::vector<int64_t>& held);
// The particles of `held` and of the tiles `tiles` of `tl`, ascending, once each.
std::vector<int64_t> with_tiles(std::vector<int64_t> held, const Tiling& tl, const std::vector<int>& tiles);
// The particles c holds x1, x2 and forces for, ascending.
std::vector<int64_t> held_particles(const Cloth& c);
// hold_particles for `held` (any order, repeats allowed) and every particle
// of the tiles `tiles` of `tl`.
void hold_with_tiles(Cloth& c, std::vector<int64_t> held, const Tiling& tl, const std::vector<int>& tiles);

}  // namespace drape
