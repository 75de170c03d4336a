#include "amrc/active_lists.hpp"

#include "amrc/quadtree.hpp"
#include "solver/kernels.hpp"

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
  const int64_t n = c.grid.n();
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
        if (c.edge_on[2 * p + d]) add(3 * n + 2 * p + d);
    });
    rows([&](int64_t p) {
      for (int d = 0; d < 2; ++d)
        if (c.triple_on[2 * p + d]) add(5 * n + 2 * p + d);
    });
    rows([&](int64_t p) {
      if (c.shear_on[p]) add(7 * n + p);
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
  auto edge = [&](int64_t s) { return c.edge_on[s] != 0; };
  auto triple = [&](int64_t s) { return c.triple_on[s] != 0; };
  auto shear = [&](int64_t s) { return c.shear_on[s] != 0; };
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

namespace {
// Shear cells: the leaves, each on the slot of its lower corner. Without a
// tree, the finest cells whose four sides are mesh edges.
void rebuild_cells(Cloth& c, bool shear_enabled, const Quadtree* tree) {
  const Grid& g = c.grid;
  for (int k = 0; k < 3; ++k) {
    c.cell[k].assign(g.n(), -1);  // same sizes during a run: no allocation
    c.corner_of[k].assign(g.n(), -1);
  }
  c.shear_on.assign(g.n(), 0);
  if (!shear_enabled) return;
  auto put = [&](int64_t s, int64_t a, int64_t b, int64_t d) {
    c.shear_on[s] = 1;
    const int64_t corner[3] = {a, b, d};
    for (int k = 0; k < 3; ++k) {
      c.cell[k][s] = corner[k];
      c.corner_of[k][corner[k]] = s;
    }
  };
  if (tree) {
    tree->for_each_leaf([&](const Cell& l) {
      const int ie = tree->i_end(l), je = tree->j_end(l);
      put(g.id(l.i, l.j), g.id(ie, l.j), g.id(l.i, je), g.id(ie, je));
    });
    return;
  }
  for (int64_t s = 0; s < g.n(); ++s) {
    const int64_t a = c.next[0][s], b = c.next[1][s];
    if (!c.active(s) || a != s + g.nj || b != s + 1) continue;
    if (c.next[1][a] == a + 1 && c.next[0][b] == b + g.nj) put(s, a, b, a + 1);
  }
}
}  // namespace

void rebuild_topology(Cloth& c, bool shear_enabled, const Quadtree* tree) {
  const Grid& g = c.grid;
  for (int d = 0; d < 2; ++d) {
    c.next[d].assign(g.n(), -1);
    c.prev[d].assign(g.n(), -1);
  }
  // Walk each grid line linking consecutive active particles.
  for (int i = 0; i < g.ni; ++i) {
    int64_t last = -1;
    for (int j = 0; j < g.nj; ++j) {
      const int64_t p = g.id(i, j);
      if (!c.active(p)) continue;
      if (last >= 0 && (!tree || tree->on_side(last, p))) {
        c.next[1][last] = p;
        c.prev[1][p] = last;
      }
      last = p;
    }
  }
  for (int j = 0; j < g.nj; ++j) {
    int64_t last = -1;
    for (int i = 0; i < g.ni; ++i) {
      const int64_t p = g.id(i, j);
      if (!c.active(p)) continue;
      if (last >= 0 && (!tree || tree->on_side(last, p))) {
        c.next[0][last] = p;
        c.prev[0][p] = last;
      }
      last = p;
    }
  }
  for (int64_t p = 0; p < g.n(); ++p) {
    const bool on = c.active(p);
    for (int d = 0; d < 2; ++d) {
      c.edge_on[2 * p + d] = on && c.next[d][p] >= 0;
      c.triple_on[2 * p + d] = on && c.next[d][p] >= 0 && c.prev[d][p] >= 0;
    }
  }
  rebuild_cells(c, shear_enabled, tree);
}

}  // namespace drape

namespace drape {

namespace {
// Half the rest distance to each active neighbour along d: the extent of cloth a particle stands for.
double extent(const Cloth& c, int64_t p, int d) {
  const int64_t st = c.grid.stride(d);
  double e = 0;
  if (c.next[d][p] >= 0) e += 0.5 * double(c.next[d][p] - p) / st;
  if (c.prev[d][p] >= 0) e += 0.5 * double(p - c.prev[d][p]) / st;
  return e * c.grid.h(d);
}
}  // namespace

void rebuild_geometry(Cloth& c, double density) {
  const Grid& g = c.grid;
  const int64_t n = g.n();
#pragma omp parallel for schedule(static)
  for (int64_t p = 0; p < n; ++p) {
    const double ext[2] = {c.active(p) ? extent(c, p, 0) : 0, c.active(p) ? extent(c, p, 1) : 0};
    c.mass[p] = density * ext[0] * ext[1];
    double len[2] = {0, 0};
    for (int d = 0; d < 2; ++d) {
      const int64_t s = 2 * p + d;
      if (c.next[d][p] >= 0) len[d] = double(c.next[d][p] - p) / g.stride(d) * g.h(d);
      c.edge_rest[s] = c.edge_on[s] ? len[d] : 0;
      c.edge_width[s] =
          c.edge_on[s] ? 0.5 * (ext[1 - d] + extent(c, c.next[d][p], 1 - d)) : 0;
      c.triple_rest[s] = c.triple_on[s] ? ext[d] : 0;
      c.triple_width[s] = c.triple_on[s] ? ext[1 - d] : 0;
    }
    // A cell stands for its own area.
    const double area = c.shear_on[p] ? double(c.cell[0][p] - p) / g.nj * g.hi * double(c.cell[1][p] - p) * g.hj : 0;
    c.shear_area[p] = area;
    c.shear_rest[p] = std::sqrt(area);
  }
}

}  // namespace drape
