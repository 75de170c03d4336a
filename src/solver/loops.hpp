#pragma once
// The loops that drive the kernels over an active list. The paper's scheme
// (active lists) splits the list into chunks, one per thread: equal at
// first, then cut where the measured times balance (ListCuts); the
// alternatives hand out whole tiles with OpenMP's static, dynamic or guided
// schedule (paper Fig. 8). Kernels write per-element results only, so every
// schedule gives bitwise the same numbers.
#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <type_traits>

#include "mesh/active_lists.hpp"
#include "solver/scene.hpp"

namespace drape {

// Where the time of the parallel loops goes, for the paper's Table 2: the
// wall time spent inside them and the thread-seconds their bodies kept
// threads busy. The rest of a step is sequential. Process-wide; only the
// master thread touches it (between loops).
struct LoopClock {
  double wall = 0, busy = 0;
};
inline LoopClock& loop_clock() {
  static LoopClock c;
  return c;
}

// What a region's body says of its own time, per thread: seconds it waited
// inside the region (at a barrier, or while one thread ran serial work), and
// seconds of serial work it ran for the team. Neither counts as busy; the
// serial work counts as sequential time, as it did outside the region.
struct RegionTime {
  double idle = 0, serial = 0;
};

// Runs body() (or body(RegionTime&)) inside one parallel region and books
// its time on loop_clock(). body must contain the work-sharing loops (nowait).
template <class Body>
void timed_region(Body&& body) {
  const double t0 = omp_get_wtime();
  double busy = 0, serial = 0;
#pragma omp parallel reduction(+ : busy, serial)
  {
    RegionTime rt;
    const double b0 = omp_get_wtime();
    if constexpr (std::is_invocable_v<Body&, RegionTime&>)
      body(rt);
    else
      body();
    busy += omp_get_wtime() - b0 - rt.idle - rt.serial;
    serial += rt.serial;
  }
  LoopClock& c = loop_clock();
  c.wall += omp_get_wtime() - t0 - serial;
  c.busy += busy;
}

// Inside a region: waits for the team, runs f() on the master thread (the
// one that may call MPI: the library runs FUNNELED), and waits again; the
// waits count as idle, f's time as serial.
template <class F>
void team_serial(RegionTime& rt, F&& f) {
  const double w0 = omp_get_wtime();
  double s = 0;
#pragma omp barrier
#pragma omp master
  {
    const double s0 = omp_get_wtime();
    f();
    s = omp_get_wtime() - s0;
  }
#pragma omp barrier
  rt.serial += s;
  rt.idle += omp_get_wtime() - w0 - s;
}

// Element-wise loop over [0, n) in equal static chunks.
template <class F>
void parallel_for(int64_t n, F&& f) {
  timed_region([&] {
#pragma omp for schedule(static) nowait
    for (int64_t k = 0; k < n; ++k) f(k);
  });
}

// Element-wise loop over index runs, the runs in equal static chunks.
template <class F>
void for_each_listed(const IndexRuns& runs, F&& f) {
  const int64_t* b = runs.bounds.data();
  const int64_t nr = runs.count();
  timed_region([&] {
#pragma omp for schedule(static) nowait
    for (int64_t r = 0; r < nr; ++r)
      for (int64_t k = b[2 * r]; k < b[2 * r + 1]; ++k) f(k);
  });
}

// Runs a loop body on items[k]; a body that takes two arguments also gets
// base + k, the item's position in the list (data kept in list order).
template <class F>
inline void visit_item(F& f, const int64_t* items, int64_t k, int64_t base) {
  if constexpr (std::is_invocable_v<F&, int64_t, int64_t>)
    f(items[k], base + k);
  else
    f(items[k]);
}

// A run of a list, positions [begin, end) of items, handed whole to a body
// that takes one (so that it may take its items four at a time); base + k
// is item k's place in the element buffers.
struct ItemRun {
  const int64_t* items;
  int64_t begin, end, base;
};

// Runs a loop body on items[k0..k1): whole, if it takes an ItemRun, else
// item by item.
template <class F>
inline void visit_run(F& f, const int64_t* items, int64_t k0, int64_t k1, int64_t base) {
  if constexpr (std::is_invocable_v<F&, const ItemRun&>) {
    if (k0 < k1) f(ItemRun{items, k0, k1, base});
  } else {
    for (int64_t k = k0; k < k1; ++k) visit_item(f, items, k, base);
  }
}

// Calls four(k) for each k = begin, begin + 4, ... with four items left in
// the run, then one(k) for each of the rest.
template <class Four, class One>
inline void in_fours(const ItemRun& run, Four&& four, One&& one) {
  int64_t k = run.begin;
  for (; k + 4 <= run.end; k += 4) four(k);
  for (; k < run.end; ++k) one(k);
}

struct LoopPolicy {
  Schedule schedule = Schedule::ActiveLists;
  int chunk = 4;  // tiles per chunk (dynamic)
};

// A small number per loop body type: each kind of pass over a list keeps its
// own cuts. Called between parallel regions only.
inline int next_pass_kind() {
  static int n = 0;
  return n++;
}
template <class F>
int pass_kind() {
  static const int kind = next_pass_kind();
  return kind;
}

// Which cuts a kind of pass (its body's type F) uses on a list; serial,
// before the parallel region that runs the pass.
template <class F>
ListCuts& cuts_for(const ActiveList& list) {
  const int chunks = omp_get_max_threads();
  constexpr size_t kKinds = 32;  // more kinds of pass share the last cuts
  if (list.cuts.size() != kKinds) {  // all at once, so a late kind allocates nothing
    list.cuts.resize(kKinds);
    for (ListCuts& c : list.cuts) c.reset(list.size(), chunks);
  }
  ListCuts& c = list.cuts[std::min(kKinds - 1, size_t(pass_kind<std::decay_t<F>>()))];
  if (!c.fits(list.size(), chunks)) c.reset(list.size(), chunks);
  return c;
}

// One pass over a list, inside a parallel region that is already running
// (work-sharing loops, no barrier at the end: a later pass that reads this
// one's results needs one). With the paper's active lists: one chunk of the
// list per thread, each timed so that the cuts follow the measured cost of
// this kind of pass (c.rebalance() after the region), then the list's tail in
// small pieces to whichever thread is free. Otherwise whole tiles, with
// OpenMP's static, dynamic or guided schedule.
// Positions handed to the body count from `base`; a body that takes an
// ItemRun gets each chunk, piece or tile whole.
template <class F>
void item_loops(const ActiveList& list, const LoopPolicy& pol, ListCuts& c, F&& f, int64_t base = 0) {
  const int64_t* items = list.items.data();
  if (pol.schedule == Schedule::ActiveLists) {
    const int chunks = int(c.cut.size()) - 1;
    const int64_t* cut = c.cut.data();
    double* seconds = c.seconds.data();
    const int64_t head = c.cut.back(), tail = c.n - head;
    const int pieces = c.pieces;
    // One chunk per thread; any other team size still covers every chunk.
#pragma omp for schedule(static, 1) nowait
    for (int q = 0; q < chunks; ++q) {
      const double t0 = omp_get_wtime();
      visit_run(f, items, cut[q], cut[q + 1], base);
      seconds[q] = omp_get_wtime() - t0;
    }
    // The tail, taken piece by piece by whoever is done first.
#pragma omp for schedule(dynamic, 1) nowait
    for (int q = 0; q < pieces; ++q)
      visit_run(f, items, head + tail * q / pieces, head + tail * (q + 1) / pieces, base);
    return;
  }
  const int nt = int(list.tile_begin.size()) - 1;
  const int64_t* tb = list.tile_begin.data();
  const int chunk = pol.chunk;
  switch (pol.schedule) {
    case Schedule::ActiveLists:  // not reached: above
    case Schedule::Static:
#pragma omp for schedule(static) nowait
      for (int t = 0; t < nt; ++t)
        visit_run(f, items, tb[t], tb[t + 1], base);
      break;
    case Schedule::Dynamic:
#pragma omp for schedule(dynamic, chunk) nowait
      for (int t = 0; t < nt; ++t)
        visit_run(f, items, tb[t], tb[t + 1], base);
      break;
    case Schedule::Guided:
#pragma omp for schedule(guided) nowait
      for (int t = 0; t < nt; ++t)
        visit_run(f, items, tb[t], tb[t + 1], base);
      break;
  }
}

// One pass in a parallel region of its own.
template <class F>
void for_each_item(const ActiveList& list, const LoopPolicy& pol, F&& f, int64_t base = 0) {
  ListCuts& c = cuts_for<F>(list);
  timed_region([&] { item_loops(list, pol, c, f, base); });
  if (pol.schedule == Schedule::ActiveLists) c.rebalance();
}

// tile_sums' loop, inside a region that is already running (no barrier at
// the end).
template <class F>
void tile_loop(const ActiveList& list, F&& value, double* out) {
  const int nt = int(list.tile_begin.size()) - 1;
#pragma omp for schedule(dynamic, 1) nowait
  for (int t = 0; t < nt; ++t) {
    double s = 0;
    for (int64_t k = list.tile_begin[t]; k < list.tile_begin[t + 1]; ++k) {
      if constexpr (std::is_invocable_v<F&, int64_t, int64_t>)
        s += value(list.items[k], k);
      else
        s += value(list.items[k]);
    }
    out[t] = s;
  }
}

// Per-tile sums of value(item) (or value(item, k), k the item's place in
// the list) over each tile's run, in list order: the fixed-order first stage
// of every reduction. out[t] for owned tile t.
template <class F>
void tile_sums(const ActiveList& list, F&& value, double* out) {
  timed_region([&] { tile_loop(list, value, out); });
}

}  // namespace drape
