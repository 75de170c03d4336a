// The memory a run holds per particle of the grid: every large array is
// listed in the owners' memory tables (the heap the world took is what they
// list), and the tables' total stays under a bound per solver.
#include <gtest/gtest.h>
#include <malloc.h>

#include <cstring>
#include <map>
#include <string>

#include "amrc/amrc.hpp"
#include "solver/memory_table.hpp"
#include "support/memory_rows.hpp"
#include "support/scenes.hpp"

namespace drape::test {
namespace {

// Bytes malloc has handed out and not taken back (arena and mmap'd blocks).
size_t heap_in_use() {
  const struct mallinfo2 m = mallinfo2();
  return m.uordblks + m.hblkhd;
}

struct Held {
  double listed = 0, heap = 0;  // bytes a particle: in the tables, taken from the heap
};

// A box drape on the finest n x n mesh, two steps (the solvers size their
// vectors at their first solve).
Held held_after_two_steps(SolverMethod method, int n) {
  Scene s;
  s.cloth.particles = {n, n};
  s.cloth.tile = 25;
  s.solver.method = method;
  const size_t before = heap_in_use();
  Held h;
  {
    Simulation w(s, test_fabric());
    w.advance(2);
    MemoryTable t;
    add_memory(t, w.cloth);
    add_memory(t, w.lists);
    w.loop->memory(t);
    const double per = 1.0 / double(w.cloth.grid.n());
    h.listed = double(t.total()) * per;
    h.heap = double(heap_in_use() - before) * per;
  }
  return h;
}

TEST(Memory, TablesListWhatTheWorldHolds) {
  held_after_two_steps(SolverMethod::Newton, 20);  // OpenMP's and the libraries' first allocations
  for (SolverMethod m : {SolverMethod::Newton, SolverMethod::Cg}) {
    const Held h = held_after_two_steps(m, 300);
    std::printf("%s: %.1f bytes a particle listed, %.1f taken from the heap\n", to_string(m), h.listed, h.heap);
    EXPECT_LE(h.listed, h.heap) << to_string(m);
    // A stray array of one float a particle would show.
    EXPECT_LE(h.heap - h.listed, 2.0) << to_string(m) << ": heap that no table lists, bytes a particle";
  }
}

// The bounds: what the tables listed at 300 x 300 when they were set, plus
// 4 bytes (a stray array of doubles would show). Newton's runs hold no nonlinear-CG vectors, the CG's no Newton ones.
TEST(Memory, BytesPerParticleStayUnderTheBound) {
  EXPECT_LE(held_after_two_steps(SolverMethod::Newton, 300).listed, 1668.0);
  EXPECT_LE(held_after_two_steps(SolverMethod::Cg, 300).listed, 1964.0);
}

// The cloth's arrays are the grid's on every rank: 247 bytes a particle
// (z 64, x1 and x2 48, mass, flags and level 10, neighbour tables 16,
// switches 5, cells' corners 24, rest geometry 80). What a step derives
// from them (bending axes, band anchors) the evaluator holds in list order;
// an array of doubles a particle added to the cloth fails here.
TEST(Memory, ClothHoldsOnlyItsGridArrays) {
  Scene s;
  s.cloth.particles = {65, 65};
  Simulation w(s, test_fabric());
  MemoryTable t;
  add_memory(t, w.cloth);
  const double per = double(t.total()) / double(w.cloth.grid.n());
  std::printf("the cloth: %.1f bytes a particle\n", per);
  EXPECT_LE(per, 248.0);
}

size_t evaluator_bytes(Simulation& w) {
  MemoryTable t;
  w.loop->evaluator().memory(t);
  return t.total();
}
// Newton's compact vectors (the first row of its table).
size_t compact_bytes(Simulation& w) {
  MemoryTable t;
  w.loop->newton().memory(t);
  return t.rows.at(0).bytes;
}

// The evaluator's arrays indexed by list position hold the lists' elements,
// not the grid's: on grid sequencing's level 2 (a sixteenth of the
// particles) its table is under a fifth of the finest mesh's. A mesh change
// that is no new stage (AMRC's) grows them where the lists outgrow them and
// keeps their capacity where they shrink; a new stage sizes them to its
// lists, back to the finest mesh's figure on level 0. Newton's compact
// vectors follow.
TEST(Memory, EvaluatorHoldsItsListsOnly) {
  Scene s;
  s.cloth.particles = {129, 129};
  s.cloth.tile = 16;
  Simulation w(s, test_fabric());
  w.step();
  const size_t finest = evaluator_bytes(w), finest_compact = compact_bytes(w);
  ASSERT_GT(finest_compact, 0u) << "the first step should have solved";
  Amrc amrc(w.cloth, 2);
  std::vector<int> all(w.tiling.count());
  for (int t = 0; t < w.tiling.count(); ++t) all[t] = t;
  auto on_level = [&](int level, bool new_stage) {
    amrc.set_uniform_level(w.cloth, w.fabric.density, s.cloth.shear, level);
    build_active_lists(w.cloth, w.tiling, all, w.lists);
    w.loop->mesh_changed(new_stage);
    w.step();
    return evaluator_bytes(w);
  };
  const size_t coarse = on_level(2, true);
  std::printf("evaluator: %zu bytes on the finest mesh, %zu on level 2\n", finest, coarse);
  EXPECT_LT(coarse, finest / 5) << "level 2's lists hold a sixteenth of the finest mesh's elements";
  EXPECT_LT(compact_bytes(w), finest_compact / 10) << "Newton's compact vectors: level 2's rows";
  const size_t grown = on_level(1, false);
  EXPECT_GT(grown, coarse) << "level 1's lists outgrow level 2's arrays";
  EXPECT_LT(grown, finest / 2);
  EXPECT_EQ(on_level(2, false), grown) << "no new stage: the capacity stays";
  EXPECT_EQ(on_level(0, true), finest) << "a new stage: sized to its lists";
  EXPECT_EQ(compact_bytes(w), finest_compact);
}

// On grid sequencing's level 2 (a sixteenth of the particles) each of those
// arrays holds under a fifth of its finest-mesh bytes: one sized by the
// grid again fails here, by name.
TEST(Memory, OnlyTheNamedArraysFollowTheGrid) {
  Scene s;
  s.cloth.particles = {129, 129};
  s.cloth.tile = 16;
  Simulation w(s, test_fabric());
  w.step();
  const std::map<std::string, size_t> finest = list_sized_rows(*w.loop);
  Amrc amrc(w.cloth, 2);
  amrc.set_uniform_level(w.cloth, w.fabric.density, s.cloth.shear, 2);
  std::vector<int> all(w.tiling.count());
  for (int t = 0; t < w.tiling.count(); ++t) all[t] = t;
  build_active_lists(w.cloth, w.tiling, all, w.lists);
  w.loop->mesh_changed(true);
  w.step();
  int checked = 0;
  for (const auto& [name, bytes] : list_sized_rows(*w.loop)) {
    const size_t before = finest.at(name);
    if (before == 0) continue;
    ++checked;
    std::printf("%-60s %9zu -> %7zu bytes\n", name.c_str(), before, bytes);
    EXPECT_LT(bytes, before / 5) << name << ": sized by the grid, not the lists?";
  }
  for (const char* must : {"Evaluator: residual", "Evaluator: particles' Newton costs",
                           "TimeLoop: saved unknowns (a step's retry)"})
    EXPECT_GT(finest.at(must), 0u) << must << ": not checked";
  EXPECT_GE(checked, 10);
}

// Keeping the products again (keep_products sizes its arrays to the lists,
// moving the others where their capacity was a finer mesh's) changes no
// result: two worlds on level 1, one toggling, land on the same bits.
TEST(Memory, KeepingProductsAgainOnACoarserMesh) {
  Scene s;
  s.cloth.particles = {33, 33};
  s.cloth.tile = 8;
  s.cloth.height = 0.401;  // contact within a few steps: Newton solves
  Simulation kept(s, test_fabric()), toggled(s, test_fabric());
  for (Simulation* w : {&kept, &toggled}) {
    Amrc amrc(w->cloth, 1);
    amrc.set_uniform_level(w->cloth, w->fabric.density, s.cloth.shear, 1);
    std::vector<int> all(w->tiling.count());
    for (int t = 0; t < w->tiling.count(); ++t) all[t] = t;
    build_active_lists(w->cloth, w->tiling, all, w->lists);
    w->loop->mesh_changed(false);  // capacity: the finest mesh's
    w->step();
  }
  toggled.loop->evaluator().keep_products(false);
  toggled.loop->evaluator().keep_products(true);
  int solved = 0;
  for (int k = 0; k < 6; ++k) {
    kept.step();
    solved += toggled.step().iterations;
  }
  EXPECT_GT(solved, 0);
  ASSERT_EQ(kept.cloth.z.size(), toggled.cloth.z.size());
  EXPECT_EQ(0, std::memcmp(kept.cloth.z.data(), toggled.cloth.z.data(), kept.cloth.z.size() * sizeof(double)));
}

// After the last step the solvers give their vectors back (the picture
// then reuses their memory); a step after that sizes them again and lands
// where a run that kept them does, bit for bit.
TEST(Memory, SolversGiveTheirVectorsBack) {
  Scene s;
  s.cloth.particles = {33, 33};
  s.cloth.tile = 8;
  s.cloth.height = 0.401;  // contact within a few steps: Newton solves
  Simulation kept(s, test_fabric()), freed(s, test_fabric());
  auto listed = [](Simulation& w) {
    MemoryTable t;
    w.loop->memory(t);
    return t.total();
  };
  for (int k = 0; k < 2; ++k) kept.step(), freed.step();
  const size_t before = listed(freed);
  freed.loop->release_solvers();
  // Its eight vectors: two at z's positions, six compact (3 a row of the evaluator's).
  const size_t newton =
      (2 * size_t(freed.cloth.layout.tension()) + 6 * 3 * freed.loop->evaluator().row_capacity()) * sizeof(double);
  EXPECT_EQ(before - listed(freed), newton);
  int solved = 0;
  for (int k = 0; k < 12; ++k) {
    kept.step();
    solved += freed.step().iterations;
  }
  EXPECT_GT(solved, 0) << "the steps after the release should have solved";
  EXPECT_EQ(listed(freed), before);
  ASSERT_EQ(kept.cloth.z.size(), freed.cloth.z.size());
  EXPECT_EQ(0, std::memcmp(kept.cloth.z.data(), freed.cloth.z.data(), kept.cloth.z.size() * sizeof(double)));
}

}  // namespace
}  // namespace drape::test
