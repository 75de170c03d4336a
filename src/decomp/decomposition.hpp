#pragma once
// One rank's share of the cloth: the tiles METIS gives it, its ghosts, and
// the reducer that sums over all ranks in tile order. With one rank: every
// tile, no ghosts, a local reducer.
#include <mpi.h>

#include <functional>
#include <memory>
#include <vector>

#include "decomp/halo_exchange.hpp"
#include "decomp/partition.hpp"
#include "decomp/reduction.hpp"

namespace drape {

struct Decomposition {
  Partition partition;
  std::vector<int> owned;  // this rank's tiles, ascending
  std::unique_ptr<HaloExchange> halo;
  std::unique_ptr<Reducer> reducer;
  const MpiReducer* mpi_reducer = nullptr;  // its timing, when there is one

  const Halo& ghosts() const { return halo ? static_cast<const Halo&>(*halo) : no_halo(); }
  // Seconds in halo exchanges and in reductions on this rank.
  double halo_seconds() const { return halo ? halo->seconds : 0.0; }
  double reduction_seconds() const { return mpi_reducer ? mpi_reducer->seconds : 0.0; }
};

// The decomposition's figures over all ranks (docs/design.md §3; docs/performance.md).
struct DecompStats {
  int tiles = 0, tile = 0;
  double imbalance = 1;
  int64_t edge_cut = 0, ghosts = 0, halo_bytes = 0, exchanges = 0;
  int ghost_width = 0, ring_width = 0;  // the halo's last plan's, in finest intervals (0: one rank)
  double halo_seconds = 0, reduction_seconds = 0;  // the largest over ranks
};

// Collective: this decomposition's figures over all ranks.
DecompStats decomp_stats(const Decomposition& d, const Tiling& tl, MPI_Comm comm);

// How far, in finest intervals, the ghosts and the element ring reach. On
// the finest mesh a triple reads its neighbours: ring 1, ghosts 2. With AMRC
// an element spans up to R = 2^max_level intervals and forces pass along
// chains of hanging particles (shorter than R), so the elements an owned
// particle gathers from sit within 2R, and what they read within 4R.
struct GhostWidths {
  int width = 2, ring = 1;
};
GhostWidths ghost_widths(bool amrc, int max_level);

// On several ranks, c's step history (x1, x2) and element forces for this rank's tiles and its
// ghosts only (hold_particles), values carried where held before; one rank
// holds the grid's.
void hold_own_particles(Cloth& c, const Tiling& tiling, const Decomposition& d);
// The halo planned anew for widths gw, the same tiles, and only the
// particles it names held (narrower: values carried, none new).
void set_ghost_widths(Decomposition& d, Cloth& c, const Tiling& tiling, GhostWidths gw);

// Collective. Throws InputError for more ranks than tiles. The tiles' work
// from the cloth's every tile, or (`counted`) from the tiles each rank
// holds (a cloth made in slots: even_share), summed over the ranks.
Decomposition decompose(const Cloth& cloth, const Tiling& tiling, MPI_Comm comm, GhostWidths gw = {},
                        const std::vector<int>* counted = nullptr);

// Collective: a new run's decomposition without any rank making the whole
// cloth. `make(held)` makes `cloth` anew (its first mesh), holding the
// particles `held` only (make_cloth's slots), and returns the mesh's ghost
// widths: first for the rank's even share of the tiles, whose work the
// partition counts, then for its own tiles' and ghosts' particles.
Decomposition decompose_in_slots(const Cloth& cloth, const Tiling& tiling, MPI_Comm comm,
                                 const std::function<GhostWidths(const std::vector<int64_t>& held)>& make);

// Before the partition: rank `rank`'s even share of the tiles (a run of
// consecutive ids), which it makes the cloth of to count their work.
std::vector<int> even_share(const Tiling& tiling, int rank, int ranks);
// The particles a rank holds: its tiles' and its ghosts', ascending (one
// rank: every particle).
std::vector<int64_t> own_particles(const Tiling& tiling, const Decomposition& d);

}  // namespace drape
