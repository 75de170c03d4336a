#pragma once
// AMRC during a run (docs/design.md §2, paper §3): every few steps, the mesh adapts
// to the cloth's bending; particles and element slots that become active get
// values interpolated from the leaf of the old mesh they lie in (positions,
// history, forces), so the state carries across; then the marks, topology,
// geometry and masses follow the new tree. Between adaptations inactive
// particles are kept on their leaf's bilinear surface (for output).
#include <cstdint>
#include <vector>

#include "amrc/criterion.hpp"
#include "mesh/quadtree.hpp"
#include "mesh/tiles.hpp"
#include "mesh/cloth.hpp"
#include "solver/contact.hpp"
#include "solver/memory_table.hpp"
#include "solver/reducer.hpp"

namespace drape {

// Where a rank computes the criterion: its tiles; `reducer` makes its bits
// whole on every rank, so every rank adapts its copy of the tree alike.
struct AdaptShare {
  const Tiling* tiling = nullptr;  // none: every particle (one rank)
  const std::vector<int>* tiles = nullptr;
  const Reducer* reducer = nullptr;
};

class Amrc {
 public:
  // `near`: room for near_sheets (self-contact), 56 bytes a grid particle
  // that a run without self-contact does not hold.
  Amrc(const Cloth& c, int max_level, bool near = false);

  const Quadtree& tree() const { return tree_; }
  // A checkpoint's tree (its finest intervals' leaf levels).
  void restore(const std::vector<uint8_t>& levels) { tree_.set_levels(levels); }

  // The criterion per particle, as criterion_bits: the indicator is the
  // largest turning angle (rad) of the mesh lines through it, at its active
  // triples (0 elsewhere), the speed its speed as the next step starts.
  void criterion(const Cloth& c, const Thresholds& th, const AdaptShare& share, std::vector<uint32_t>& out) const;
  // Per particle, where the mesh would place it inside the obstacle (the
  // mask criterion.hpp's adapt takes): bit 0, on the leaf it lies in now;
  // bit l, on the level-l cell round it, merged.
  void inside(const Cloth& c, const Obstacle& ob, const AdaptShare& share, std::vector<uint32_t>& out) const;
  // Per active particle, the near mask criterion.hpp's adapt takes, for
  // self-contact at pair distance D: bit l, a particle of the cloth that is
  // not its mesh neighbour lies within split_reach(l), bit kKeepFine + l,
  // within keep_reach(l) (levels up to one above its coarsest leaf's).
  // Only pairs of particles are checked, so a leaf must split while another
  // sheet could still reach its surface unseen (near.cpp).
  void near_sheets(const Cloth& c, double pair_distance, const AdaptShare& share, std::vector<uint32_t>& out);

  // One adaptation of the tree to the cloth; when the mesh changes, carries
  // the state over and rebuilds the cloth's mesh (the caller rebuilds lists).
  // With several ranks each carries the state of its own particles (and of
  // its ghosts, which must be current, hanging ones included).
  // With an obstacle, no leaf's surface cuts into it (the floor, flat, never is).
  AdaptStats adapt(Cloth& c, double density, bool shear, const Thresholds& th, const AdaptShare& share = {},
                   const Obstacle* obstacle = nullptr);

  // The tree given as its finest intervals' leaf levels, the state carried
  // over as adapt() does. Between runs of time steps, like adapt().
  void set_levels(Cloth& c, double density, bool shear, const std::vector<uint8_t>& levels);
  // Grid sequencing (sequence.hpp): every leaf at `level`.
  void set_uniform_level(Cloth& c, double density, bool shear, int level);

  // Applies the current tree to the cloth (marks, topology, geometry, masses).
  void apply(Cloth& c, double density, bool shear) const;

  // Moves the particles the last adaptation made free out of the contact
  // layer, with their history: on the old leaf's flat surface (or its side,
  // where they hung) they may start inside it (the leaf spanned an edge of
  // the box), and the contact would throw them out at tens of m/s.
  void lift_new_particles(Cloth& c, const Contact& contact) const;

  // Puts inactive particles on the bilinear surface of their leaf.
  void fill_inactive(Cloth& c) const;

  // Its arrays' capacities (both trees, the criterion's fields, the old mesh's marks).
  void memory(MemoryTable& t) const;

 private:
  // After tree_ changed from old_: the new mesh, with the state carried over.
  void carry_over(Cloth& c, double density, bool shear);
  void carry_shear(Cloth& c) const;
  void make_room_near(const Cloth& c);

  Quadtree tree_, old_;
  std::vector<uint32_t> marks_, inside_, near_;  // the criterion's bits (criterion.hpp)
  // near_sheets's: the active particles (ids, positions) packed in id order,
  // each particle's packed index (-1: inactive), and the boxes of a pyramid
  // of grid tiles (from tile_offset_[k] at level k; near.cpp).
  std::vector<int32_t> packed_ids_, packed_at_;
  std::vector<double> packed_x_, tile_box_;
  std::vector<int64_t> tile_offset_;
  std::vector<Cell> cells_;  // adapt's scratch, reserved for every leaf
  std::vector<uint8_t> was_active_, was_free_, edge_on_, triple_on_, shear_on_;  // the old mesh's
};

}  // namespace drape
