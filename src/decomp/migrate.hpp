#pragma once
// Data migration after a repartition (docs/design.md §3): tiles whose owner changes
// move with everything their particles carry between steps — positions and
// forces (z), the step history (x1, x2), flags and levels — one message per
// pair of ranks, tiles in ascending id, particles in grid order within each.
// Derived data (masses, rest geometry, bend axes, lists) is rebuilt after.
#include <mpi.h>

#include <cstdint>
#include <vector>

#include "mesh/tiles.hpp"
#include "mesh/cloth.hpp"

namespace drape {

struct MigrationStats {
  int tiles_moved = 0;  // over all ranks
  int64_t bytes = 0;    // sent, over all ranks
};

// Renames the parts of `fresh` (a new partition) so that each lands on the
// rank that already holds most of its work: fewer tiles move. Greedy on the
// largest overlap first, ties to the lowest ids, so every rank agrees.
std::vector<int> relabel_to_overlap(const std::vector<int>& old_owner, const std::vector<int>& fresh,
                                    const std::vector<int64_t>& work, int ranks);

// Bytes a tile's migration sends (its particles' z, history, flags, level).
int64_t tile_migration_bytes(const Tiling& tiling, int tile);

// Collective: moves every tile whose owner differs between the two maps.
MigrationStats migrate_tiles(Cloth& c, const Tiling& tiling, const std::vector<int>& old_owner,
                             const std::vector<int>& new_owner, MPI_Comm comm);

}  // namespace drape
