#pragma once
// The state checksum (DESIGN §4): every particle's positions, element forces
// and flags are hashed together with its global id, and the hashes summed
// (mod 2^64, two independent lanes). A sum is the same in any order, so the
// digest identifies the state however the particles were split over ranks,
// threads and tiles.
#include <cstdint>
#include <string>

#include "solver/cloth.hpp"
#include "decomp/tiles.hpp"
#include "solver/reducer.hpp"

namespace drape {

struct Checksum {
  uint64_t lane[2] = {0, 0};
  std::string hex() const;
};

// Sums over the particles of the given tiles; the reducer adds the ranks.
Checksum state_checksum(const Cloth& c, const Tiling& tiling, const std::vector<int>& tiles,
                        const Reducer& red);

}  // namespace drape
