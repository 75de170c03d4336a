#pragma once
// Grid-scale zigzag: a mesh line that turns one way at a particle and back
// at the next folds the cloth at the mesh spacing itself. No finer mesh
// repeats such a fold (its own spacing is smaller), so where a drape has
// many, its shape depends on the mesh. On the box drapes they lay mostly in
// the cloth's plane, where shear read per particle (a cross's mean) did not
// see them (an hourglass mode, docs/design.md §1); shear read per
// cell does. report.json's `zigzag` counts them in the final state.
#include <cstdint>
#include <vector>

#include "mesh/cloth.hpp"
#include "solver/reducer.hpp"

namespace drape {

// rad: turns below this are smooth bending, not a kink (0.1 rad at the
// 7.8 mm spacing of a 1 m, 129 x 129 cloth is a curvature of 13 1/m).
inline constexpr double kZigzagTurn = 0.1;

struct Zigzag {
  int64_t pairs = 0;    // neighbouring particles on a mesh line, both with a bending triple
  int64_t zigzags = 0;  // of them, pairs that turn by more than min_turn each, in opposite senses
  double share() const { return pairs > 0 ? double(zigzags) / pairs : 0.0; }
};

// Over `particles` (each rank its own) and the next particle along each
// direction. Collective (the reducer's sums). Reads positions up to two
// active particles away: the ghosts must be current.
Zigzag count_zigzags(const Cloth& c, const std::vector<int64_t>& particles, const Reducer& red,
                     double min_turn = kZigzagTurn);

}  // namespace drape
