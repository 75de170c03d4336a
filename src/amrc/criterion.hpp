#pragma once
// The AMRC criterion (paper §3): refine where the bending is large, coarsen
// where it is small, with a gap between the two thresholds so that a cell
// does not flip back and forth.
#include <cstdint>
#include <vector>

#include "mesh/quadtree.hpp"

namespace drape {

struct AdaptStats {
  int refined = 0, coarsened = 0;
  int refined_inside = 0;  // of `refined`, the splits the inside mask alone asked for
  int refined_near = 0;    // of `refined`, the splits the near mask alone asked for
};

// The near mask's bits that keep a cell from forming start here (those that
// split a leaf: from bit 1, one a level; max_level is at most 10).
constexpr unsigned kKeepFine = 16;

// AmrcSpec's values as the criterion reads them (no defaults of its own: a
// forgotten refine/coarsen fails adapt()'s coarsen < refine check).
struct Thresholds {
  double refine = 0, coarsen = 0;
  double coarsen_speed = 0;  // > 0: merge only where every particle is slower
  // Scale each leaf's indicator by its width over the coarsest leaf's
  // (AmrcIndicator::Deflection): finer leaves need sharper turns to split.
  bool by_width = false;
  // > 0: self-contact's pair distance D; leaves near another part of the
  // cloth split until self-contact sees it (Amrc::near_sheets).
  double pair_distance = 0;
};

// What adapt() asks of a particle, as bits, so that the ranks' answers or
// together (4 bytes a particle instead of the fields' values): bit l, its
// indicator times the level-l scale exceeds `refine` (a level-l leaf holding
// it splits); bit kBlocksMerge + l, that product is not below `coarsen`
// (no cell whose children are level l merges over it); kMoving, not slower
// than `coarsen_speed` (when that is set). The same tests as on the largest
// value: a rounded product is monotone in the value.
constexpr unsigned kBlocksMerge = 16;
constexpr uint32_t kMoving = 1u << 31;
uint32_t criterion_bits(double indicator, double speed, const Thresholds& th, int max_level);

// One pass: every leaf whose largest indicator (over the particles of its
// closed cell) exceeds `refine` splits; then every cell whose children are
// all leaves with indicators below `coarsen` merges (2:1 balance permitting).
// `marks` has one criterion_bits word per particle (the run's indicator is
// the turning angle). `scratch` holds the leaves (reserve (NI-1)(NJ-1) to
// adapt without allocating). With a speed in the marks (kMoving), a cell
// merges only where every particle is also slower than `coarsen_speed`.
// With `inside` (one mask per particle): bit 0 set, the
// mesh places the particle inside an obstacle, and every leaf holding it
// splits (and no cell holding it merges); bit l set, merging the level-l
// cell round it would, and the cell stays split. A leaf spanning a box's edge cuts through the box with its
// flat surface; split later, its particles would start deep inside.
// With `near` (one mask per particle; Amrc::near_sheets):
// bit l set, another part of the cloth lies close enough for a level-l leaf
// holding the particle to let it pass through unseen by self-contact, and
// that leaf splits; bit kKeepFine + l set, a level-l cell holding it would
// come too close, and it stays split.
AdaptStats adapt(Quadtree& tree, const std::vector<uint32_t>& marks, const Thresholds& th,
                 std::vector<Cell>& scratch, const std::vector<uint32_t>* inside = nullptr,
                 const std::vector<uint32_t>* near = nullptr);
// The same from the fields' values (one per particle; `speed` only with
// th.coarsen_speed > 0).
AdaptStats adapt(Quadtree& tree, const std::vector<double>& indicator, const Thresholds& th,
                 std::vector<Cell>& scratch, const std::vector<double>* speed = nullptr,
                 const std::vector<uint32_t>* inside = nullptr, const std::vector<uint32_t>* near = nullptr);
inline AdaptStats adapt(Quadtree& tree, const std::vector<double>& indicator, double refine, double coarsen) {
  std::vector<Cell> scratch;
  return adapt(tree, indicator, Thresholds{refine, coarsen}, scratch);
}

}  // namespace drape
