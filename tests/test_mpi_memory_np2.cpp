// Two ranks: each rank's evaluator holds the elements of its own tiles and
// of its ghost ring (its arrays in list order), not the grid's.
#include <gtest/gtest.h>
#include <mpi.h>

#include <malloc.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <new>

#include "app/simulation.hpp"
#include "decomp/decomposition.hpp"
#include "io/checkpoint.hpp"
#include "io/config.hpp"
#include "solver/memory_table.hpp"
#include "support/files.hpp"
#include "support/memory_rows.hpp"
#include "support/scenes.hpp"

// The heap's live bytes and their peak, through operator new and delete.
namespace {
std::atomic<int64_t> g_live{0}, g_peak{0};
void count(void* p, int64_t sign) {
  if (!p) return;
  const int64_t now = g_live += sign * int64_t(malloc_usable_size(p));
  int64_t peak = g_peak;
  while (now > peak && !g_peak.compare_exchange_weak(peak, now)) {
  }
}
}  // namespace

void* operator new(std::size_t n) {
  void* p = std::malloc(n ? n : 1);
  if (!p) throw std::bad_alloc();
  count(p, 1);
  return p;
}
namespace {
// Out of line: inlined beside operator new, std::free draws a mismatched-delete warning.
[[gnu::noinline]] void drop(void* p) noexcept {
  count(p, -1);
  std::free(p);
}
}  // namespace
void operator delete(void* p) noexcept { drop(p); }
void operator delete(void* p, std::size_t) noexcept { drop(p); }

namespace drape::test {
namespace {

// As the program sets a new run up on the finest mesh (no tree): the
// cloth made in slots, never whole.
Decomposition set_up_in_slots(const Scene& s, const Fabric& f, const Tiling& tl, Cloth& cloth) {
  return decompose_in_slots(cloth, tl, MPI_COMM_WORLD, [&](const std::vector<int64_t>& held) {
    cloth = Cloth();
    cloth = make_cloth(s, f, &held);
    return ghost_widths(false, 0);
  });
}

// This rank's tiles of the scene on two ranks, and its time loop.
struct RankRun {
  Tiling tiling;
  Cloth cloth;
  Decomposition dec;
  Model model;
  ActiveLists lists;
  LoopPolicy policy;
  std::unique_ptr<TimeLoop> loop;
  RankRun(const Scene& s, const Fabric& f)
      : tiling(s.cloth.particles[0], s.cloth.particles[1], s.cloth.tile),
        dec(set_up_in_slots(s, f, tiling, cloth)),
        model(make_model(s, f, cloth.grid.hi, cloth.grid.hj)),
        policy{s.parallel.schedule, s.parallel.chunk} {
    build_active_lists(cloth, tiling, dec.owned, lists, dec.halo->ring());
    loop = std::make_unique<TimeLoop>(cloth, model, lists, tiling, policy, *dec.reducer, s.solver, dec.ghosts());
  }
};

// The heap's peak, in bytes above what was live before, while `make` runs.
template <class F>
int64_t heap_peak(F make) {
  g_peak = g_live.load();
  const int64_t before = g_live;
  make();
  return g_peak - before;
}

size_t evaluator_bytes(TimeLoop& loop) {
  MemoryTable t;
  loop.evaluator().memory(t);
  return t.total();
}

// A new run is set up on two ranks without making the whole cloth on
// either: each makes its half of the tiles to count their work, then its
// own tiles' and ghosts' particles. The heap's peak while it does is under
// 0.8 of making the whole cloth (one rank's set-up; 0.70 at 257 x 257: the
// grid's rows, z's positions, flags, level and the slot map, 30 bytes a
// particle, and the rest for half the cloth and its ghosts). Making the
// whole cloth first and narrowing it to the rank's particles peaks above it.
TEST(MemoryNp2, SetUpMakesOnlyTheRanksParticles) {
  Scene s;
  s.cloth.particles = {257, 257};
  s.cloth.tile = 16;
  const Fabric f = test_fabric();
  const Tiling tl(s.cloth.particles[0], s.cloth.particles[1], s.cloth.tile);
  const int64_t whole = heap_peak([&] { Cloth c = make_cloth(s, f); });
  Cloth cloth;
  Decomposition dec;
  const int64_t mine = heap_peak([&] { dec = set_up_in_slots(s, f, tl, cloth); });
  int64_t most = 0;
  MPI_Allreduce(&mine, &most, 1, MPI_INT64_T, MPI_MAX, MPI_COMM_WORLD);
  const double n = double(cloth.grid.n());
  std::printf("set-up's heap peak: whole cloth %.1f bytes a grid particle, the larger rank's of two %.1f (%.2f)\n",
              double(whole) / n, double(most) / n, double(most) / double(whole));
  EXPECT_LT(double(most), 0.8 * double(whole)) << "the whole cloth made on a rank?";
  // What it made: its own tiles' and ghosts' particles, in slots.
  EXPECT_EQ(held_particles(cloth), own_particles(tl, dec));
  EXPECT_LT(double(cloth.layout.m), 0.65 * n);
}

// A restart on two ranks reads its own tiles' and ghosts' particles from
// the checkpoint (their rows' hyperslabs), never the whole state: its
// set-up's heap peaks within 1.1 of a new run's on two ranks (1.00 at
// 257 x 257). Reading the checkpoint whole on each rank, 114 bytes a
// particle, and making the whole cloth to narrow it, peak far above.
TEST(MemoryNp2, RestartReadsOnlyTheRanksParticles) {
  Scene s;
  s.cloth.particles = {257, 257};
  s.cloth.tile = 16;
  s.solver.steps = 1;
  s.output.checkpoint_every = 1;
  s.output.every = 0;
  s.output.picture = false;
  const Fabric f = test_fabric();
  RunOptions opt;
  opt.output_dir = (std::filesystem::path(DRAPE_TEST_TMP) / "memory_np2_restart").string();
  opt.quiet = true;
  opt.scene_toml = scene_to_toml(s);
  {
    Simulation sim(s, f, opt, MPI_COMM_WORLD);
    ASSERT_EQ(sim.run(), 0);
  }
  const int64_t fresh = heap_peak([&] { Simulation sim(s, f, opt, MPI_COMM_WORLD); });
  const int64_t resumed = heap_peak([&] {
    const CheckpointState ck = read_checkpoint(opt.output_dir + "/checkpoint.h5");
    RunOptions again = opt;
    again.restart = &ck;
    Simulation sim(s, f, again, MPI_COMM_WORLD);
    EXPECT_EQ(sim.cloth.step, 1);
  });
  int64_t mine[2] = {fresh, resumed}, most[2];
  MPI_Allreduce(mine, most, 2, MPI_INT64_T, MPI_MAX, MPI_COMM_WORLD);
  const double n = double(s.cloth.particles[0]) * s.cloth.particles[1];
  std::printf("set-up's heap peak on the larger rank of two: new run %.1f bytes a grid particle, restart %.1f (%.2f)\n",
              double(most[0]) / n, double(most[1]) / n, double(most[1]) / double(most[0]));
  EXPECT_LT(double(most[1]), 1.1 * double(most[0])) << "the checkpoint read whole on a rank?";
}

// Half the tiles and a ring of one particle: well under two thirds of one
// rank's table (the ring's elements are the rest). Arrays sized by the
// grid would give 1.
TEST(MemoryNp2, EvaluatorHoldsItsOwnTiles) {
  Scene s;
  s.cloth.particles = {129, 129};
  s.cloth.tile = 16;
  const Fabric f = test_fabric();
  Simulation one(s, f);
  one.step();
  const size_t whole = evaluator_bytes(*one.loop);

  RankRun run(s, f);
  TimeLoop& loop = *run.loop;
  Timers tm;
  loop.step(tm);
  const size_t mine = evaluator_bytes(loop);
  std::printf("evaluator: %zu bytes on one rank, %zu on this one of two\n", whole, mine);
  EXPECT_LT(double(mine), 0.65 * double(whole));
  // Each of the time loop's arrays but the ones named as the grid's
  // (memory_rows.hpp): the residual, particle costs, saved unknowns and
  // Newton's compact vectors too.
  const std::map<std::string, size_t> whole_rows = list_sized_rows(*one.loop);
  int checked = 0;
  for (const auto& [name, bytes] : list_sized_rows(loop)) {
    const size_t all = whole_rows.at(name);
    if (all == 0) continue;
    ++checked;
    EXPECT_LT(double(bytes), 0.65 * double(all)) << name << ": sized by the grid, not this rank's lists?";
  }
  EXPECT_GE(checked, 10);
  // With Jacobi no rank gathers the finest level.
  MemoryTable t;
  loop.memory(t);
  EXPECT_TRUE(listed(t, kGatheredLevel));
  EXPECT_EQ(row_bytes(t, kGatheredLevel), 0u);
  EXPECT_TRUE(listed(t, kGatheredVectors));
  EXPECT_EQ(row_bytes(t, kGatheredVectors), 0u);
}

// The step history (x1, x2, 48 bytes a grid particle on one rank), z's
// forces (40), the masses (8), the neighbour tables (16), the cells'
// corners (24) and the element switches (5) hold this rank's tiles and its
// ghosts: under 0.6 of the grid's on one of two ranks (0.54). Their
// slot map (4 bytes a particle) and z's positions (24) are the grid's.
// After a few steps each own particle's history, forces, mass, neighbours,
// cells and switches are one rank's, bit for bit.
TEST(MemoryNp2, HistoryForcesAndCellsHoldTheirOwnTilesAndGhosts) {
  Scene s;
  s.cloth.particles = {65, 65};
  s.cloth.tile = 8;
  const Fabric f = test_fabric();
  Simulation one(s, f);
  RankRun run(s, f);
  const Cloth& c = run.cloth;
  const double n = double(c.grid.n());
  MemoryTable t;
  add_memory(t, c);
  const double history = double(row_bytes(t, "Cloth: x1, x2 (earlier positions)"));
  const double forces = double(row_bytes(t, "Cloth: z's forces"));
  const double cells = double(row_bytes(t, "Cloth: cell, corner_of (shear cells' corners)"));
  const double mass = double(row_bytes(t, "Cloth: mass"));
  const double neighbours = double(row_bytes(t, "Cloth: next, prev (neighbour tables)"));
  const double switches = double(row_bytes(t, "Cloth: element switches"));
  std::printf("x1, x2: %.1f, z's forces: %.1f, cells: %.1f, mass: %.1f, neighbours: %.1f, switches: %.2f bytes a grid "
              "particle on this rank of two\n",
              history / n, forces / n, cells / n, mass / n, neighbours / n, switches / n);
  EXPECT_LT(history, 0.6 * 48 * n) << "x1, x2 sized by the grid, not this rank's tiles and ghosts?";
  EXPECT_LT(forces, 0.6 * 40 * n) << "z's forces sized by the grid, not this rank's tiles and ghosts?";
  EXPECT_LT(cells, 0.6 * 24 * n) << "cells' corners sized by the grid, not this rank's tiles and ghosts?";
  EXPECT_LT(mass, 0.6 * 8 * n) << "masses sized by the grid, not this rank's tiles and ghosts?";
  EXPECT_LT(neighbours, 0.6 * 16 * n) << "neighbour tables sized by the grid, not this rank's tiles and ghosts?";
  EXPECT_LT(switches, 0.6 * 5 * n) << "element switches sized by the grid, not this rank's tiles and ghosts?";
  EXPECT_EQ(row_bytes(t, "Cloth: z's positions"), size_t(24 * n));
  EXPECT_EQ(row_bytes(t, "Cloth: slots of x1, x2, the forces, masses, neighbours and cells (several ranks)"), size_t(4 * n));
  Timers tm;
  for (int k = 0; k < 3; ++k) {
    one.step();
    run.loop->step(tm);
  }
  const Cloth& whole = one.cloth;
  int64_t own = 0, differ = 0, forces_differ = 0, cells_differ = 0, mass_differ = 0, neighbours_differ = 0,
          switches_differ = 0;
  for (int tile : run.dec.owned) {
    const TileRange r = run.tiling.range(tile);
    for (int i = r.i0; i < r.i1; ++i)
      for (int j = r.j0; j < r.j1; ++j, ++own) {
        const int64_t p = c.grid.id(i, j);
        for (int k = 0; k < 3; ++k)
          differ += c.x1_at(p)[k] != whole.x1[3 * p + k] || c.x2_at(p)[k] != whole.x2[3 * p + k];
        for (int b = 0; b < 3; ++b)
          for (int64_t e = b < 2 ? 2 * p : p; e < (b < 2 ? 2 * p + 2 : p + 1); ++e)
            forces_differ += c.force(b, e) != whole.force(b, e);
        for (int k = 0; k < 3; ++k)
          cells_differ += c.cell_at(k, p) != whole.cell_at(k, p) || c.corner_at(k, p) != whole.corner_at(k, p);
        mass_differ += c.mass_at(p) != whole.mass_at(p);
        for (int d = 0; d < 2; ++d)
          neighbours_differ += c.next_at(d, p) != whole.next_at(d, p) || c.prev_at(d, p) != whole.prev_at(d, p);
        for (int64_t s : {2 * p, 2 * p + 1})
          switches_differ += c.edge_on_at(s) != whole.edge_on_at(s) || c.triple_on_at(s) != whole.triple_on_at(s);
        switches_differ += c.shear_on_at(p) != whole.shear_on_at(p);
      }
  }
  EXPECT_GT(own, 0);
  EXPECT_EQ(differ, 0) << "own particles' history differs from one rank's";
  EXPECT_EQ(forces_differ, 0) << "own particles' element forces differ from one rank's";
  EXPECT_EQ(cells_differ, 0) << "own particles' cells differ from one rank's";
  EXPECT_EQ(mass_differ, 0) << "own particles' masses differ from one rank's";
  EXPECT_EQ(neighbours_differ, 0) << "own particles' neighbours differ from one rank's";
  EXPECT_EQ(switches_differ, 0) << "own particles' element switches differ from one rank's";
}

// The multigrid on two ranks, its finest level divided: no rank receives
// K whole. At a build each receives level 1's rows (a row's length, 8
// bytes, a block's column and values, 4 + 72) and the power iteration's
// vector at its start and each step (24 bytes a particle; 12 steps cold,
// 3 warm); at a V-cycle, level 1's right-hand side (24 bytes a level-1
// particle). The gathered K's row holds nothing and the gathered vectors'
// row no more than its vectors and maps.
TEST(MemoryNp2, MultigridGathersLevelOneNotK) {
  Scene s;
  s.cloth.particles = {33, 33};
  s.cloth.tile = 8;
  s.cloth.height = 0.401;  // contact within a few steps: Newton solves
  s.solver.method = SolverMethod::Newton;
  s.solver.preconditioner = Preconditioner::Multigrid;
  const Fabric f = test_fabric();
  RankRun run(s, f);
  Cloth& cloth = run.cloth;
  const ActiveLists& lists = run.lists;
  TimeLoop& loop = *run.loop;
  Timers tm;
  for (int k = 0; k < 6; ++k) loop.step(tm);
  const NewtonSolver& newton = loop.newton();
  ASSERT_GT(newton.multigrid_builds(), 0);
  ASSERT_GE(newton.multigrid_stats().size(), 2u);
  const MultigridLevelStats& finest = newton.multigrid_stats()[0];
  const MultigridLevelStats& one = newton.multigrid_stats()[1];
  ASSERT_GT(finest.cycles, 0);
  const int64_t rows = finest.points, blocks = finest.blocks;
  EXPECT_GT(rows, lists.particles.size());  // the other rank's rows counted too
  const int64_t whole = 76 * blocks + 8 * rows, level_one = 76 * one.blocks + 8 * one.points, vector = 24 * rows;
  EXPECT_LT(2 * level_one, whole);
  const int64_t last = newton.multigrid_build_bytes() - level_one, builds = newton.multigrid_builds();
  EXPECT_TRUE(last == 4 * vector || last == 13 * vector) << newton.multigrid_build_bytes();
  // The pattern stays (no AMRC, no self-contact): level 1's bytes at every build.
  const int64_t vectors = newton.multigrid_builds_bytes() - builds * level_one;
  EXPECT_EQ(vectors % vector, 0);
  EXPECT_GE(vectors, 4 * builds * vector);
  EXPECT_LE(vectors, 13 * builds * vector);
  // The finest level divided: a cycle gathers level 1's right-hand side
  // only, and exchanges the ghosts' entries (24 bytes each a time).
  EXPECT_EQ(newton.multigrid_cycle_bytes(), 24 * one.points);
  EXPECT_GT(newton.multigrid_ghosts(), 0);
  EXPECT_GT(newton.multigrid_exchanged_bytes(), 0);
  EXPECT_EQ(newton.multigrid_cycles_bytes(), finest.cycles * newton.multigrid_cycle_bytes());
  MemoryTable t;
  loop.memory(t);
  const size_t k_held = row_bytes(t, kGatheredLevel), vectors_held = row_bytes(t, kGatheredVectors),
               divided = row_bytes(t, kDividedLevel);
  std::printf("multigrid on a rank of two: %lld rows, %lld blocks (K whole %lld bytes), level 1 %lld bytes; held: K "
              "%zu, vectors and maps %zu, divided level %zu\n",
              (long long)rows, (long long)blocks, (long long)whole, (long long)level_one, k_held, vectors_held,
              divided);
  EXPECT_EQ(k_held, 0u);
  // The whole cycle's right-hand side, result and the concatenation (3
  // doubles a row each), the maps (the global order's particles, its rows
  // in the concatenation, 8 bytes a row each; the grid's column numbers, 4
  // a particle) and this rank's rows' (8 each): no more.
  const int64_t own = lists.particles.size();
  EXPECT_LE(vectors_held, size_t(3 * 24 * rows + 2 * 8 * rows + 8 * own + 4 * cloth.grid.n() + 64));
  EXPECT_GT(divided, 0u);
}

// The whole cycle gathered on request (solver.multigrid_divided = false,
// the reference): each rank gathers the whole right-hand side (24 bytes a
// free particle a cycle) and exchanges nothing, and the own particles end
// where the divided cycle's do, bit for bit.
TEST(MemoryNp2, MultigridGathersTheWholeCycleOnRequest) {
  Scene s;
  s.cloth.particles = {33, 33};
  s.cloth.tile = 8;
  s.cloth.height = 0.401;
  s.solver.method = SolverMethod::Newton;
  s.solver.preconditioner = Preconditioner::Multigrid;
  const Fabric f = test_fabric();
  RankRun divided(s, f);
  s.solver.multigrid_divided = false;
  RankRun whole(s, f);
  Timers tm;
  for (int k = 0; k < 6; ++k) {
    divided.loop->step(tm);
    whole.loop->step(tm);
  }
  const NewtonSolver& nw = whole.loop->newton();
  const NewtonSolver& nd = divided.loop->newton();
  ASSERT_GT(nw.multigrid_stats().size(), 1u);
  ASSERT_GT(nw.multigrid_stats()[0].cycles, 0);
  EXPECT_EQ(nw.multigrid_cycle_bytes(), 24 * nw.multigrid_stats()[0].points);
  EXPECT_EQ(nw.multigrid_exchanged_bytes(), 0);
  EXPECT_GT(nd.multigrid_exchanged_bytes(), 0);
  EXPECT_EQ(nw.multigrid_stats()[0].cycles, nd.multigrid_stats()[0].cycles);
  int64_t differ = 0;
  for (int64_t p : divided.lists.particles.items)
    for (int k = 0; k < 3; ++k) differ += divided.cloth.z[3 * p + k] != whole.cloth.z[3 * p + k];
  EXPECT_GT(divided.lists.particles.size(), 0);
  EXPECT_EQ(differ, 0) << "own particles differ between the divided and the whole cycle";
}

}  // namespace
}  // namespace drape::test
