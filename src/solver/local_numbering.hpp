#pragma once
// A rank's own numbering of the particles its product vectors hold
// (docs/design.md §3): first its free particles in the particle list's
// order (so index r is the compact vectors' row r), then the hanging
// particles in the hanging list's order (the rows after), then the others
// that its elements, hanging chains or self-contact pairs touch (its
// clamped particles, the ghosts, the contact ghosts), ascending. A ghost nothing here reads has no index (the halo
// drops it); an own particle with none is sent as 0. Vectors so numbered are sized by the rank's
// region, not the grid. A grid id is found by binary searches (its tile's
// part of the particle list, the hanging ids, the others), done when the
// lists change, never per product.
#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "mesh/active_lists.hpp"
#include "mesh/tiles.hpp"
#include "solver/fit.hpp"

namespace drape {

class LocalNumbering {
 public:
  // The free and hanging particles of `lists` (called first: the others
  // are what index_of_listed does not find).
  void list(const ActiveLists& lists, const Tiling& tiling, bool exact) {
    lists_ = &lists;
    tiling_ = &tiling;
    const size_t nh = lists.hanging.size();
    room(hanging_, lists.hanging, 1, exact);
    hanging_.resize(nh);
    for (size_t i = 0; i < nh; ++i) hanging_[i] = {lists.hanging[i].h, int32_t(i)};
    std::sort(hanging_.begin(), hanging_.end());
    others_.clear();
  }
  // Adds a particle that is neither free here nor hanging (repeats allowed).
  void add_other(int64_t p) { others_.push_back(p); }
  // After the last add_other: the others sorted, each once.
  void seal() {
    std::sort(others_.begin(), others_.end());
    others_.erase(std::unique(others_.begin(), others_.end()), others_.end());
  }
  // Room for `n` others (called before add_other): where short, grown
  // with an eighth to spare (fit.hpp's rule), or with `exact` made n.
  void reserve_others(size_t n, bool exact) {
    if (exact ? others_.capacity() != n : others_.capacity() < n) {
      std::vector<int64_t> fresh;
      fresh.reserve(exact ? n : n + n / 8);
      others_.swap(fresh);
    }
  }
  size_t others_capacity() const { return others_.capacity(); }

  int64_t free_count() const { return lists_->particles.size(); }
  int64_t size() const { return free_count() + int64_t(hanging_.size() + others_.size()); }
  // p's index if it is a free particle of this rank's or a hanging one, else -1.
  int64_t index_of_listed(int64_t p) const {
    const int64_t f = index_of_free(p);
    if (f >= 0) return f;
    const auto h = std::lower_bound(hanging_.begin(), hanging_.end(), std::pair<int64_t, int32_t>{p, INT32_MIN});
    return h != hanging_.end() && h->first == p ? free_count() + h->second : -1;
  }
  // Any particle's index, -1 where it has none (after seal).
  int64_t index_of(int64_t p) const {
    const int64_t l = index_of_listed(p);
    if (l >= 0) return l;
    const auto o = std::lower_bound(others_.begin(), others_.end(), p);
    return o != others_.end() && *o == p ? free_count() + int64_t(hanging_.size()) + (o - others_.begin()) : -1;
  }
  // The grid id of index l.
  int64_t id_of(int64_t l) const {
    const int64_t nf = free_count(), nh = int64_t(hanging_.size());
    if (l < nf) return lists_->particles.items[size_t(l)];
    if (l < nf + nh) return lists_->hanging[size_t(l - nf)].h;
    return others_[size_t(l - nf - nh)];
  }
  // v with room for `per` entries a hanging particle the lists have room
  // for (AMRC reserves it up front: no allocation as they come and go);
  // with `exact`, just that.
  template <class T>
  static void room(std::vector<T>& v, const std::vector<HangingLink>& hanging, size_t per, bool exact) {
    const size_t n = per * std::max(hanging.size(), hanging.capacity());
    if (exact ? v.capacity() != n : v.capacity() < n) {
      std::vector<T> fresh;
      fresh.reserve(n);
      v.swap(fresh);
    }
  }
  size_t bytes() const {
    return hanging_.capacity() * sizeof(hanging_[0]) + others_.capacity() * sizeof(int64_t);
  }

 private:
  // Its position in its tile's part of the particle list (ascending).
  int64_t index_of_free(int64_t p) const {
    const std::vector<int>& tiles = lists_->tiles;
    const auto k = std::lower_bound(tiles.begin(), tiles.end(), tiling_->tile_of(p));
    if (k == tiles.end() || *k != tiling_->tile_of(p)) return -1;
    const ActiveList& pl = lists_->particles;
    const size_t kt = size_t(k - tiles.begin());
    const int64_t *b = pl.items.data() + pl.tile_begin[kt], *e = pl.items.data() + pl.tile_begin[kt + 1];
    const int64_t* f = std::lower_bound(b, e, p);
    return f != e && *f == p ? f - pl.items.data() : -1;
  }
  const ActiveLists* lists_ = nullptr;
  const Tiling* tiling_ = nullptr;
  std::vector<std::pair<int64_t, int32_t>> hanging_;  // (id, place in the hanging list), by id
  std::vector<int64_t> others_;                       // ascending
};

}  // namespace drape
