// Results do not depend on how many threads ran them, nor on the schedule:
// the state checksum and the final cost are bitwise the same for 1-4 threads
// and for active lists, static, dynamic and guided (docs/design.md §3).
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <string>

#include "amrc/criterion.hpp"
#include "solver/checksum.hpp"
#include "support/scenes.hpp"

namespace drape::test {
namespace {

struct Outcome {
  std::string checksum;
  double cost;
  int iterations;
};

Outcome run(int threads, Schedule schedule) {
  Scene s;
  s.cloth.particles = {23, 19};  // tiles of 5: uneven, clipped at the borders
  s.cloth.size = {0.3, 0.25};
  s.cloth.tile = 5;
  s.cloth.height = 0.1 + 0.0068 + 0.0005;  // just above the contact margin (h/2)
  s.obstacle.center = {0.0, 0.0, 0.05};
  s.obstacle.size = {0.1, 0.1, 0.1};
  s.solver.dt = 2e-3;
  s.solver.max_iterations = 300;
  s.parallel.schedule = schedule;
  s.parallel.chunk = 2;
  omp_set_num_threads(threads);
  Simulation w(s, test_fabric());
  Outcome out{};
  StepStats st;
  for (int k = 0; k < 6; ++k) {
    st = w.step();
    out.iterations += st.iterations;
  }
  out.cost = st.cost.total();
  std::vector<int> all;
  for (int t = 0; t < w.tiling.count(); ++t) all.push_back(t);
  out.checksum = state_checksum(w.cloth, w.tiling, all, w.red()).hex();
  return out;
}

TEST(Determinism, SameBitsForEveryThreadCountAndSchedule) {
  const Outcome ref = run(1, Schedule::ActiveLists);
  ASSERT_GT(ref.iterations, 10) << "the scene should make the solver work (contact)";
  for (Schedule sc : {Schedule::ActiveLists, Schedule::Static, Schedule::Dynamic, Schedule::Guided})
    for (int threads : {1, 2, 3, 4}) {
      const Outcome o = run(threads, sc);
      EXPECT_EQ(o.checksum, ref.checksum) << to_string(sc) << ", " << threads << " threads";
      EXPECT_EQ(std::memcmp(&o.cost, &ref.cost, sizeof(double)), 0)
          << to_string(sc) << ", " << threads << " threads: " << o.cost << " vs " << ref.cost;
      EXPECT_EQ(o.iterations, ref.iterations);
    }
}

TEST(Checksum, ChangesWithAnyBitOfTheState) {
  Scene s = flat_scene(6, 5, 0.1, 0.1);
  Simulation w(s, test_fabric());
  std::vector<int> all;
  for (int t = 0; t < w.tiling.count(); ++t) all.push_back(t);
  const std::string a = state_checksum(w.cloth, w.tiling, all, w.red()).hex();
  w.cloth.z[w.cloth.layout.moment() + 7] = 1e-300;  // one tiny moment
  const std::string b = state_checksum(w.cloth, w.tiling, all, w.red()).hex();
  EXPECT_NE(a, b);
  EXPECT_EQ(a.size(), 32u);
}

}  // namespace
}  // namespace drape::test

namespace drape::test {
namespace {

// Every item of an active list is visited exactly once, whatever the list's
// length against the thread count, the tile split and the schedule.
TEST(ActiveLists, EveryItemProcessedExactlyOnce) {
  for (int threads : {1, 2, 3, 4}) {
    omp_set_num_threads(threads);
    for (int64_t n : {0, 1, 2, 3, 4, 5, 7, 8, 13, 64, 1001, 2047, 2048, 2049, 40000}) {
      ActiveList list;
      for (int64_t k = 0; k < n; ++k) list.items.push_back(3 * k + 1);  // sparse slot ids
      const int tiles = 5;  // uneven runs, some empty
      for (int t = 0; t <= tiles; ++t) list.tile_begin.push_back(n * t * t / (tiles * tiles));
      for (Schedule sc : {Schedule::ActiveLists, Schedule::Static, Schedule::Dynamic, Schedule::Guided}) {
        std::vector<int> seen(3 * n + 2, 0);
        for_each_item(list, LoopPolicy{sc, 1}, [&](int64_t s) { seen[s] += 1; });
        for (int64_t k = 0; k < n; ++k)
          ASSERT_EQ(seen[3 * k + 1], 1) << to_string(sc) << ", " << threads << " threads, n " << n;
        int64_t total = 0;
        for (int v : seen) total += v;
        ASSERT_EQ(total, n);
      }
    }
  }
}

// Newton's compact vectors (Minimizer: unknowns below the tension block
// numbered in tile order): for_each_unknown numbers exactly the free
// particles' positions, 0 .. unknowns_below - 1 once each; tile_sums hands
// its body the same numbers; compact_sums over a compact vector is bit for
// bit tile_sums over the same values at z's indices; and the numbering
// follows a rebuild of the lists. On a plain mesh and on an AMRC mesh with
// coarse leaves, hanging particles and a clamped corner.
TEST(ActiveLists, CompactNumbersAreTheFreeParticlesPositions) {
  for (bool amrc : {false, true}) {
    Scene s;
    s.cloth.particles = {23, 19};
    s.cloth.size = {0.3, 0.25};
    s.cloth.tile = 5;
    Simulation w(s, test_fabric());
    if (amrc) {
      Quadtree t(23, 19, 2);
      const std::vector<double> flat(23 * 19, 0.0);
      for (int pass = 0; pass < 4; ++pass) adapt(t, flat, 1.0, 0.5);
      t.refine(t.leaf_at(9, 5));
      w.set_tree(t);
    }
    w.cloth.flags[0] |= kFixed;
    w.rebuild();
    Minimizer& m = w.loop->minimizer();
    const int64_t end = w.cloth.layout.tension();
    for (int64_t fixed : {int64_t(0), int64_t(23 * 19 - 1)}) {
      const std::string where = std::string(amrc ? "AMRC mesh" : "plain mesh") + ", fixed " + std::to_string(fixed);
      if (fixed > 0) {  // the same minimizer after its lists are built again (a new stamp)
        m.unknowns_below(end);
        w.cloth.flags[fixed] |= kFixed;
        std::vector<int> owned;
        for (int t = 0; t < w.tiling.count(); ++t) owned.push_back(t);
        build_active_lists(w.cloth, w.tiling, owned, w.lists);
        if (w.tree()) hanging_links(*w.tree(), w.lists.hanging);
      }
      std::vector<int64_t> want;
      for (int64_t p : w.lists.particles.items)
        for (int a = 0; a < 3; ++a) want.push_back(3 * p + a);
      std::sort(want.begin(), want.end());
      ASSERT_LT(want.size(), 3 * size_t(w.cloth.grid.n()) - (amrc ? 100 : 2)) << "some particles are not free";
      const int64_t n = m.unknowns_below(end);
      ASSERT_EQ(n, int64_t(want.size())) << where;
      std::vector<int64_t> at(n, -1), again(n, -1);
      std::vector<int> hits(n, 0);
      std::atomic<int> outside{0};  // no assertions inside the parallel loop
      m.for_each_unknown(end, [&](int64_t c, int64_t k) {
        if (c < 0 || c >= n) {
          ++outside;
          return;
        }
        at[c] = k;
        ++hits[c];
      });
      ASSERT_EQ(outside.load(), 0) << where << ": numbers outside 0 .. " << n - 1;
      EXPECT_EQ(hits, std::vector<int>(n, 1)) << where;
      std::vector<int64_t> got = at;
      std::sort(got.begin(), got.end());
      EXPECT_EQ(got, want) << where;
      double unused;
      m.tile_sums<1>(end, [&](int64_t c, int64_t k, double*) { again[c] = k; }, &unused);
      EXPECT_EQ(again, at) << where << ": tile_sums numbers the unknowns otherwise";
      std::vector<double> compact(n), spread(w.cloth.z.size(), 0.0);
      for (int64_t c = 0; c < n; ++c) spread[at[c]] = compact[c] = std::sin(1.0 + double(c)) * (1 + c % 7);
      double a, b;
      m.tile_sums<1>(end, [&](int64_t k, double* acc) { acc[0] += spread[k] * spread[k]; }, &a);
      m.compact_sums<1>(end, [&](int64_t c, double* acc) { acc[0] += compact[c] * compact[c]; }, &b);
      EXPECT_EQ(a, b) << where;
    }
  }
}

// The threads' cuts of an active list follow the measured time: on a list
// whose first half costs three times as much per item, simulated passes move
// the cuts until the chunks' times agree; the bounds always cover the list.
TEST(ActiveLists, CutsFollowTheMeasuredTime) {
  for (int threads : {1, 2, 3, 4}) {
    for (int64_t n : {0, 1, 2, 5, 1000, 99999}) {
      ListCuts c;
      c.reset(n, threads);
      auto cost = [&](int64_t a, int64_t b) {  // items [a, b): 3 each below n/2, 1 above
        const int64_t h = n / 2;
        return 3.0 * double(std::max<int64_t>(0, std::min(b, h) - a)) +
               double(std::max<int64_t>(0, b - std::max(a, h)));
      };
      for (int pass = 0; pass < 30; ++pass) {
        for (int q = 0; q < threads; ++q) c.seconds[q] = 1e-6 * cost(c.cut[q], c.cut[q + 1]);
        c.rebalance();
        ASSERT_EQ(c.cut.front(), 0);
        ASSERT_EQ(c.cut.back(), n - (c.pieces > 0 ? n / 16 : 0)) << "the head ends where the tail starts";
        for (int q = 0; q < threads; ++q) ASSERT_LE(c.cut[q], c.cut[q + 1]);
      }
      if (n < 1000 || threads == 1) continue;
      double most = 0;
      for (int q = 0; q < threads; ++q) most = std::max(most, cost(c.cut[q], c.cut[q + 1]));
      const double even = cost(0, c.cut.back()) / threads;
      EXPECT_LT(most, 1.01 * even) << threads << " threads, n " << n;
      EXPECT_LT(c.cut[1], n / threads) << "the costly first chunk should have shrunk";
    }
  }
}

}  // namespace
}  // namespace drape::test
