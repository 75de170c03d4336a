#pragma once
// Positions of element slots in the active lists, found by walking the
// lists beside a run of particles taken in list order (ascending within a
// tile). The slots one place of a row names (the edge into p, the cell p is
// corner 2 of, ...) then mostly ascend too, so each place keeps cursors into
// the lists and moves them forward a little; a slot behind its cursor (an
// uneven AMRC mesh, a new tile) is searched for in the part passed over. No
// map by slot: that would be sized by the grid on every rank.
#include <algorithm>
#include <cstdint>

#include "mesh/active_lists.hpp"
#include "mesh/cloth.hpp"
#include "mesh/tiles.hpp"

namespace drape {

class ListWalk {
 public:
  static constexpr int kPlaces = int(sizeof(GatherRow::at) / sizeof(int32_t));
  ListWalk(const ActiveLists& lists, const Tiling& tiling) : lists_(lists), tiling_(tiling) {}

  // Slot s of kind (0 edge, 1 triple, 2 cell), asked for at `place`: its
  // position (the ring's after this rank's own), -1 in no list.
  int64_t position(int place, int kind, int64_t s) {
    const int tile = tiling_.tile_of(kind == 2 ? s : s >> 1);
    Cursor& c = cursor(place, kind, tile);
    const int64_t* f = c.find(s);
    return f != c.end && *f == s ? c.base + (f - c.begin) : -1;
  }

 private:
  // A part of one list that holds a tile's slots (the ring for a tile this
  // rank does not own), and how far the walk has come in it: every item
  // before `at` is below the slot last asked for.
  struct Cursor {
    int tile = -1, kind = -1;
    const int64_t *begin = nullptr, *end = nullptr, *at = nullptr;
    int64_t base = 0;  // the position of begin
    const int64_t* find(int64_t s) {
      if (at > begin && at[-1] >= s) return at = std::lower_bound(begin, at, s);  // went back
      return at = gallop(at, end, s);
    }
  };
  // The first item >= s in [lo, e), all of [.., lo) below s: probes 1, 2,
  // 4, ... ahead, so a walk in small steps reads a few items a slot. The
  // probe that stops is >= s: the answer is at most there.
  static const int64_t* gallop(const int64_t* lo, const int64_t* e, int64_t s) {
    int64_t step = 1;
    while (step < e - lo && lo[step] < s) {
      lo += step;
      step *= 2;
    }
    return std::lower_bound(lo, lo + std::min(step, int64_t(e - lo)), s);
  }
  // Two cursors a place: a tile's particles take a place's slots from their
  // own tile and, along one side, from one neighbour. The one used less
  // lately makes room for a new part.
  Cursor& cursor(int place, int kind, int tile) {
    Cursor* two = last_[place];
    if (two[0].tile == tile && two[0].kind == kind) return two[0];
    std::swap(two[0], two[1]);
    if (two[0].tile != tile || two[0].kind != kind) open(two[0], kind, tile);
    return two[0];
  }
  void open(Cursor& c, int kind, int tile) const {
    const ActiveList* own[3] = {&lists_.edges, &lists_.triples, &lists_.shears};
    const ActiveList* ring[3] = {&lists_.ring_edges, &lists_.ring_triples, &lists_.ring_shears};
    const ActiveList& o = *own[kind];
    c.tile = tile;
    c.kind = kind;
    const std::vector<int>& tiles = lists_.tiles;
    const auto k = std::lower_bound(tiles.begin(), tiles.end(), tile);
    if (k != tiles.end() && *k == tile) {  // this rank's tile: its part of the list
      const size_t kt = size_t(k - tiles.begin());
      c.base = o.tile_begin[kt];
      c.begin = o.items.data() + c.base;
      c.end = o.items.data() + o.tile_begin[kt + 1];
    } else {
      const ActiveList& r = *ring[kind];
      c.base = o.size();
      c.begin = r.items.data();
      c.end = c.begin + r.size();
    }
    c.at = c.begin;
  }
  const ActiveLists& lists_;
  const Tiling& tiling_;
  Cursor last_[kPlaces][2];
};

}  // namespace drape
