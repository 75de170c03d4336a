#pragma once
// Rebalance after AMRC (docs/design.md §3): a new mesh changes each tile's work;
// when the ranks' loads drift apart by more than the allowed imbalance,
// boundary tiles move from the most loaded ranks to their neighbours (few
// tiles move); if that cannot reach the allowed imbalance, the tile graph is
// partitioned again with METIS and the new parts renamed to overlap the old
// ones most. The tiles that change owner migrate with their state, and the
// halo is planned again for the new owners.
#include <mpi.h>

#include <cstdint>
#include <vector>

#include "decomp/decomposition.hpp"

namespace drape {

struct Rebalance {
  int step = 0;
  double imbalance_before = 1, imbalance_after = 1;  // max / mean work per rank
  int tiles_moved = 0;
  int64_t bytes_moved = 0;  // over all ranks
  int64_t edge_cut = 0;     // the new partition's
  const char* method = "";  // "diffusion" or "metis"
};

// Moves tiles one at a time from the most loaded rank to a neighbouring
// rank (8-neighbour tiles) while that lowers the largest load, until the
// imbalance is within `target`. The same on every rank (deterministic ties);
// no MPI, so the scale model runs it for any number of ranks.
std::vector<int> diffuse_tiles(const Tiling& tl, std::vector<int> owner, const std::vector<int64_t>& work,
                               int ranks, double target);

// Collective. Measures the current partition against the cloth's work; above
// `threshold`, repartitions and migrates when that lowers the imbalance.
// Returns whether tiles moved; `out` gets the figures (imbalance_before is
// always set). d.owned, d.partition and d.halo then describe the new layout.
bool rebalance(Decomposition& d, Cloth& c, const Tiling& tl, double threshold, MPI_Comm comm,
               Rebalance& out);

}  // namespace drape
