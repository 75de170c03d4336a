#pragma once
// The paper's active lists (§4.3): one list per element type of the slots
// that are active now, sorted by tile and then by index, with the start of
// each tile's run. Threads split a list into chunks (ListCuts); reductions
// sum each tile's run in order, so results do not depend on the thread count.
// Rebuilt after AMRC changes the mesh; capacity is reserved once.
#include <cstdint>
#include <vector>

#include "mesh/tiles.hpp"
#include "mesh/cloth.hpp"

namespace drape {

// How a list is split among the threads: one chunk each, then a shared
// tail. The paper cuts equal counts. On an uneven mesh equal counts are not
// equal times (a coarse region's elements lie far apart in memory and cost
// more each), so the cuts start equal and, after every pass, move halfway
// towards where the threads' measured times would have been equal. Each
// kind of pass over a list (forces, gradient, ...) has its own cuts: their
// costs per item differ. What cuts cannot foresee (another process taking a
// core for a moment) the tail absorbs: the list's last 1/16, in small pieces
// that threads take as they finish their chunks. Which thread does an item
// never changes a result (kernels write per element).
struct ListCuts {
  std::vector<int64_t> cut;     // threads + 1 bounds into the list's head [0, cut.back())
  std::vector<int64_t> next;    // scratch for rebalance()
  std::vector<double> seconds;  // each chunk's time in the last pass
  int64_t n = 0;                // the list's length: [cut.back(), n) is the tail
  int pieces = 0;               // the tail's pieces
  bool fits(int64_t len, int threads) const { return int(cut.size()) == threads + 1 && n == len; }
  void reset(int64_t len, int threads);  // equal counts
  void rebalance();                      // serial, after a pass
};

struct ActiveList {
  std::vector<int64_t> items;       // slot or particle indices
  std::vector<int64_t> tile_begin;  // size tiles+1: items of tile k are [tile_begin[k], tile_begin[k+1])
  mutable std::vector<ListCuts> cuts;  // the threads' chunks, per kind of pass (loops.hpp)
  int64_t size() const { return int64_t(items.size()); }
};

// A hanging particle h on the coarse side a-b: x_h = (1 - t) x_a + t x_b.
struct HangingLink {
  int64_t h, a, b;
  double t;
};

// Index ranges [begin, end) into z, kept per tile: contiguous runs, so that
// loops over them stay simple and vectorise.
struct IndexRuns {
  std::vector<int64_t> bounds;      // begin, end of run 0, begin, end of run 1, ...
  std::vector<int64_t> tile_begin;  // runs of tile k: [tile_begin[k], tile_begin[k+1])
  int64_t count() const { return int64_t(bounds.size() / 2); }
};

struct ActiveLists {
  ActiveList particles;  // free particles (their positions are unknowns)
  ActiveList edges;      // edge slots 2p+d
  ActiveList triples;    // triple slots 2p+d
  ActiveList shears;     // shear slots p
  std::vector<int> tiles;  // the tiles this rank owns, ascending
  // The unknowns of those tiles as indices into z, tile by tile and in z's
  // block order within a tile (positions, tensions, moments, shears): vector
  // updates and dot products run over these only, so the inactive entries of
  // an AMRC mesh cost nothing.
  IndexRuns unknowns;
  // The same entries in ascending order, adjacent runs merged and cut into
  // pieces of at most 4096: vector updates stream through z (no tiles).
  IndexRuns unknown_spans;
  // Elements of the ghost ring (other ranks' tiles, one particle around this
  // rank's): computed here too, because this rank's particles gather their
  // contributions; their cost belongs to their owner. One run, no tiles.
  ActiveList ring_edges, ring_triples, ring_shears;
  // AMRC's hanging particles, finest sides first (an end may itself hang on
  // a coarser side): positions follow their ends; forces and gradients on
  // them pass to their ends. Empty without AMRC. Filled right after
  // build_active_lists (hanging_links), never changed on its own: the
  // evaluator's rows for it follow the stamp below (and its size).
  std::vector<HangingLink> hanging;
  // A number no other build of any lists had: whoever keeps data in list
  // order (the evaluator's buffers, rows and neighbour copies) sees that the
  // lists changed.
  uint64_t stamp = 0;
};

// Builds the lists over `owned_tiles` (ascending tile ids) from the cloth's
// flags and element switches, and the ring lists over `ring` (ascending
// particle ids, none on one rank). Reuses the lists' capacity.
void build_active_lists(const Cloth& c, const Tiling& tiling, const std::vector<int>& owned_tiles,
                        ActiveLists& out, const std::vector<int64_t>& ring = {});

}  // namespace drape
