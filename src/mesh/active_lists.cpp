#include "mesh/active_lists.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>

namespace drape {

namespace {

template <class Pred>
void build_one(const Tiling& tiling, const std::vector<int>& owned, int per_particle, Pred on,
               ActiveList& list) {
  list.items.clear();
  list.tile_begin.assign(owned.size() + 1, 0);
  for (size_t k = 0; k < owned.size(); ++k) {
    list.tile_begin[k] = int64_t(list.items.size());
    const TileRange r = tiling.range(owned[k]);
    for (int i = r.i0; i < r.i1; ++i)
      for (int j = r.j0; j < r.j1; ++j) {
        const int64_t p = int64_t(i) * tiling.nj + j;
        for (int d = 0; d < per_particle; ++d) {
          const int64_t s = per_particle * p + d;
          if (on(s)) list.items.push_back(s);
        }
      }
  }
  list.tile_begin[owned.size()] = int64_t(list.items.size());
}

// Per tile: for each block of z, for each row, the entries of its active
// unknowns in ascending order (the order of a full tile-ordered dot product).
void build_unknowns(const Cloth& c, const Tiling& tiling, const std::vector<int>& owned, IndexRuns& runs) {
  std::vector<int64_t>& b = runs.bounds;
  b.clear();
  runs.tile_begin.assign(owned.size() + 1, 0);
  for (size_t k = 0; k < owned.size(); ++k) {
    runs.tile_begin[k] = runs.count();
    // Extends the tile's last run or starts one (runs never cross tiles).
    auto add = [&](int64_t u) {
      if (runs.count() > runs.tile_begin[k] && b.back() == u) {
        b.back() = u + 1;
      } else {
        b.push_back(u);
        b.push_back(u + 1);
      }
    };
    const TileRange r = tiling.range(owned[k]);
    auto rows = [&](auto&& visit) {
      for (int i = r.i0; i < r.i1; ++i)
        for (int j = r.j0; j < r.j1; ++j) visit(int64_t(i) * tiling.nj + j);
    };
    rows([&](int64_t p) {
      if (c.free(p))
        for (int a = 0; a < 3; ++a) add(3 * p + a);
    });
    rows([&](int64_t p) {
      for (int d = 0; d < 2; ++d)
        if (c.edge_on_at(2 * p + d)) add(c.force_index(0, 2 * p + d));
    });
    rows([&](int64_t p) {
      for (int d = 0; d < 2; ++d)
        if (c.triple_on_at(2 * p + d)) add(c.force_index(1, 2 * p + d));
    });
    rows([&](int64_t p) {
      if (c.shear_on_at(p)) add(c.force_index(2, p));
    });
  }
  runs.tile_begin[owned.size()] = runs.count();
}

void build_spans(const IndexRuns& runs, IndexRuns& spans) {
  const int64_t nr = runs.count();
  std::vector<int64_t>& s = spans.bounds;
  s.clear();
  // Runs are ascending within each tile's block rows; sort the run starts.
  std::vector<int64_t>& order = spans.tile_begin;  // scratch: run ids by start
  order.resize(nr);
  for (int64_t r = 0; r < nr; ++r) order[r] = r;
  std::sort(order.begin(), order.end(),
            [&](int64_t x, int64_t y) { return runs.bounds[2 * x] < runs.bounds[2 * y]; });
  const int64_t piece = 4096;
  for (int64_t r : order) {
    int64_t b = runs.bounds[2 * r];
    const int64_t e = runs.bounds[2 * r + 1];
    if (!s.empty() && s.back() == b && s.back() - s[s.size() - 2] < piece) {  // extend the last piece
      const int64_t room = piece - (s.back() - s[s.size() - 2]);
      const int64_t take = std::min(room, e - b);
      s.back() += take;
      b += take;
    }
    for (; b < e; b += piece) {
      s.push_back(b);
      s.push_back(std::min(e, b + piece));
    }
  }
  spans.tile_begin.clear();
}

template <class Pred>
void build_ring(const std::vector<int64_t>& ring, int per_particle, Pred on, ActiveList& list) {
  list.items.clear();
  for (int64_t p : ring)
    for (int d = 0; d < per_particle; ++d)
      if (on(per_particle * p + d)) list.items.push_back(per_particle * p + d);
  list.tile_begin = {0, int64_t(list.items.size())};
}

}  // namespace

void ListCuts::reset(int64_t len, int threads) {
  n = len;
  // A tail only where each piece still holds enough items to be worth a handout.
  pieces = threads > 1 ? 4 * threads : 0;
  const int64_t tail = pieces > 0 && len >= 256 * pieces ? len / 16 : 0;
  if (tail == 0) pieces = 0;
  const int64_t head = len - tail;
  cut.resize(threads + 1);
  next.resize(threads + 1);
  seconds.assign(threads, 0.0);
  for (int t = 0; t <= threads; ++t) cut[t] = head * t / threads;
}

void ListCuts::rebalance() {
  const int T = int(cut.size()) - 1;
  if (T <= 1) return;
  const int64_t head = cut[T];  // the tail is not cut
  double total = 0;
  for (double s : seconds) total += s;
  if (head == 0 || !(total > 0)) return;
  const double mean = total / double(head);  // per item, for chunks without items
  // Where the cumulative measured time (linear within each chunk) reaches
  // k/T of the total: the cut that would have balanced the last pass.
  int q = 0;
  double before = 0;  // time of the chunks before q
  next[0] = 0;
  next[T] = head;
  for (int k = 1; k < T; ++k) {
    const double want = total * k / T;
    while (q < T - 1 && before + seconds[q] < want) before += seconds[q++];
    const int64_t len = cut[q + 1] - cut[q];
    const double per = len > 0 && seconds[q] > 0 ? seconds[q] / double(len) : mean;
    const double x = double(cut[q]) + (want - before) / per;
    next[k] = std::clamp<int64_t>(int64_t(x), cut[q], cut[q + 1]);
  }
  for (int k = 1; k < T; ++k)  // halfway: damps the noise of one pass
    cut[k] = std::clamp<int64_t>(cut[k] + (next[k] - cut[k]) / 2, cut[k - 1], head);
}

void build_active_lists(const Cloth& c, const Tiling& tiling, const std::vector<int>& owned,
                        ActiveLists& out, const std::vector<int64_t>& ring) {
  static std::atomic<uint64_t> builds{0};
  out.stamp = ++builds;
  out.tiles = owned;
  auto edge = [&](int64_t s) { return c.edge_on_at(s); };
  auto triple = [&](int64_t s) { return c.triple_on_at(s); };
  auto shear = [&](int64_t s) { return c.shear_on_at(s); };
  build_one(tiling, owned, 1, [&](int64_t p) { return c.free(p); }, out.particles);
  build_one(tiling, owned, 2, edge, out.edges);
  build_one(tiling, owned, 2, triple, out.triples);
  build_one(tiling, owned, 1, shear, out.shears);
  build_unknowns(c, tiling, owned, out.unknowns);
  build_spans(out.unknowns, out.unknown_spans);
  build_ring(ring, 2, edge, out.ring_edges);
  build_ring(ring, 2, triple, out.ring_triples);
  build_ring(ring, 1, shear, out.ring_shears);
}

}  // namespace drape
