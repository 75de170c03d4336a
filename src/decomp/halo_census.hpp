#pragma once
// What the halo exchange of every rank would send and receive for a given
// map of tile owners, counted without MPI and for all ranks at once: the
// scale model's figures for thousands of ranks come from one process. The
// rule is HaloExchange's (halo_exchange.hpp): a particle goes to every other
// rank that owns a particle within `width` of it in the max norm; two
// ranks are neighbours when either sends to the other. A 2-rank test
// checks these counts against a real HaloExchange's plan.
#include <cstdint>
#include <vector>

#include "mesh/tiles.hpp"

namespace drape {

struct HaloCensus {
  std::vector<int64_t> sent;      // per rank: particles sent per exchange (one per receiving rank)
  std::vector<int64_t> received;  // per rank: ghosts
  std::vector<int> neighbours;    // per rank: ranks it exchanges with
};

// `width` must not exceed the tile side (windows reach adjacent tiles only).
HaloCensus halo_census(const Tiling& tiling, const std::vector<int>& owner, int parts, int width = 2);

}  // namespace drape
