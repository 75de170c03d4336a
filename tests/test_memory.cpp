// The memory a run holds per particle of the grid: every large array is
// listed in the owners' memory tables (the heap the world took is what they
// list), and the tables' total stays under a bound per solver.
#include <gtest/gtest.h>
#include <malloc.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <string>

#include "amrc/amrc.hpp"
#include "amrc/criterion.hpp"
#include "amrc/remesh.hpp"
#include "solver/memory_table.hpp"
#include "support/memory_rows.hpp"
#include "support/scenes.hpp"

namespace drape::test {
namespace {

int64_t own_size(const ActiveLists& l, int kind) {
  const ActiveList* own[3] = {&l.edges, &l.triples, &l.shears};
  return own[kind]->size();
}

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
  EXPECT_LE(held_after_two_steps(SolverMethod::Newton, 300).listed, 1194.0);  // self-contact's pair search 76 of it
  EXPECT_LE(held_after_two_steps(SolverMethod::Cg, 300).listed, 1468.0);
}

// The cloth's arrays on one rank are the grid's: 167 bytes a particle
// (z 64, x1 and x2 48, mass, flags and level 10, neighbour tables 16,
// switches 5, cells' corners 24). What a step derives from them (rest
// geometry, bending axes, band anchors) the evaluator holds in list order;
// an array of doubles a particle added to the cloth fails here.
TEST(Memory, ClothHoldsOnlyItsGridArrays) {
  Scene s;
  s.cloth.particles = {65, 65};
  Simulation w(s, test_fabric());
  MemoryTable t;
  add_memory(t, w.cloth);
  const double per = double(t.total()) / double(w.cloth.grid.n());
  std::printf("the cloth: %.1f bytes a particle\n", per);
  EXPECT_LE(per, 168.0);
}

// AMRC's room for the near-sheet search (56 bytes a grid particle) is held
// where AMRC adapts with self-contact (on by default), not by grid
// sequencing's tree, which never searches.
TEST(Memory, OnlyAdaptingAmrcHoldsTheNearSheetRoom) {
  for (bool adapting : {false, true}) {
    Scene s;
    s.cloth.particles = {65, 65};
    s.amrc.enabled = adapting;
    ASSERT_TRUE(s.solver.self_contact);
    RunOptions opt;  // the drape program's set-up: a tree for grid sequencing too
    opt.output_dir = std::string(DRAPE_TEST_TMP) + "/near_room_" + std::to_string(int(adapting));
    opt.quiet = true;
    Simulation w(s, test_fabric(), opt, MPI_COMM_SELF);
    ASSERT_TRUE(w.amrc) << "grid sequencing or AMRC: a tree";
    MemoryTable t;
    w.amrc->memory(t);
    size_t room = 0;
    for (const MemoryTable::Row& r : t.rows)
      if (r.array == "near sheets' packed particles and tile boxes") room = r.bytes;
    if (adapting)
      EXPECT_GT(room, 0u) << "AMRC with self-contact: the near rule's room";
    else
      EXPECT_EQ(room, 0u) << "grid sequencing holds the near rule's room";
  }
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
// arrays holds under a fifth of its finest-mesh bytes, with either solver:
// one sized by the grid again fails here, by name.
TEST(Memory, OnlyTheNamedArraysFollowTheGrid) {
  for (SolverMethod method : {SolverMethod::Newton, SolverMethod::Cg}) {
    Scene s;
    s.cloth.particles = {129, 129};
    s.cloth.tile = 16;
    s.solver.method = method;
    Simulation w(s, test_fabric());
    w.lists.hanging.reserve(8);  // room for hanging links, as AMRC's lists hold: their buffers are checked too
    w.step();
    const std::map<std::string, size_t> finest = list_sized_rows(*w.loop);
    Amrc amrc(w.cloth, 2);
    amrc.set_uniform_level(w.cloth, w.fabric.density, s.cloth.shear, 2);
    std::vector<int> all(w.tiling.count());
    for (int t = 0; t < w.tiling.count(); ++t) all[t] = t;
    build_active_lists(w.cloth, w.tiling, all, w.lists);
    std::vector<HangingLink>(1).swap(w.lists.hanging);  // a coarse mesh's room for fewer links
    w.lists.hanging.clear();
    w.loop->mesh_changed(true);
    w.step();
    int checked = 0;
    for (const auto& [name, bytes] : list_sized_rows(*w.loop)) {
      const size_t before = finest.at(name);
      if (before == 0) continue;
      ++checked;
      std::printf("%s: %-60s %9zu -> %7zu bytes\n", to_string(method), name.c_str(), before, bytes);
      EXPECT_LT(bytes, before / 5) << to_string(method) << ": " << name << ": sized by the grid, not the lists?";
    }
    const char* solver_row = method == SolverMethod::Cg ? "Minimizer: g, g new, s, d, z0, diagonal (nonlinear CG, compact)"
                                                        : "NewtonSolver: d, r, s, diagonal (compact); p, K p (own numbering)";
    for (const char* must : {"Evaluator: residual", "Evaluator: particles' Newton costs",
                             "Evaluator: hanging particles' forces and results",
                             "Evaluator: rest geometry (lengths, widths)",
                             "TimeLoop: saved unknowns (a step's retry)", solver_row})
      EXPECT_GT(finest.at(must), 0u) << to_string(method) << ": " << must << ": not checked";
    EXPECT_GE(checked, 10) << to_string(method);
  }
}

// The evaluator's two largest rows hold what the kernels need and no more,
// bytes a grid particle of a finest 129 x 129 Newton run (2 edges, 2
// triples and a cell a particle, a little less at the borders): the element
// buffers an edge's one entry (3 doubles: its ends' are each other's
// negatives), a triple's and a cell's one number (times the kept
// gradients), 9 doubles; the kept numbers an edge's 2 (its frozen tension
// and slope: its direction and length computed from z again), a triple's 7
// (kept_bend) and a cell's 13, 31 doubles (a particle's contact terms
// computed again, none kept). K's frozen
// slopes and tensions, which the kept numbers carry, are held only by an
// evaluator that does not keep them; a nonlinear CG run holds neither.
// Both ends' entries of an edge, a triple's or a cell's contributions to
// each particle, or the frozen slopes beside the kept numbers held again
// fail here.
TEST(Memory, ElementBuffersAndKeptNumbersHoldNoMore) {
  Scene s;
  s.cloth.particles = {129, 129};
  s.cloth.tile = 16;
  s.solver.method = SolverMethod::Newton;
  Simulation w(s, test_fabric());
  w.step();
  MemoryTable t;
  w.loop->evaluator().memory(t);
  const double per = 1.0 / double(w.cloth.grid.n());
  const double buffers = double(row_bytes(t, "Evaluator: element buffers (edges, triples, cells)")) * per;
  const double kept = double(row_bytes(t, "Evaluator: products' kept numbers (elements)")) * per;
  std::printf("element buffers %.1f, kept numbers %.1f bytes a particle\n", buffers, kept);
  EXPECT_GT(buffers, 0.95 * 9 * 8);
  EXPECT_LE(buffers, 9 * 8);
  EXPECT_GT(kept, 0.95 * 31 * 8);
  EXPECT_LE(kept, 31 * 8);
  const std::string frozen = "Evaluator: K's frozen slopes and tensions";
  EXPECT_EQ(row_bytes(t, frozen), 0u);
  w.loop->evaluator().keep_products(false);
  MemoryTable off;
  w.loop->evaluator().memory(off);
  EXPECT_GT(double(row_bytes(off, frozen)) * per, 0.95 * 7 * 8) << "not keeping, the products read them";
  EXPECT_EQ(row_bytes(off, "Evaluator: products' kept numbers (elements)"), 0u);
  s.solver.method = SolverMethod::Cg;
  Simulation cg(s, test_fabric());
  cg.step();
  MemoryTable c;
  cg.loop->evaluator().memory(c);
  EXPECT_EQ(row_bytes(c, "Evaluator: products' kept numbers (elements)"), 0u) << "nonlinear CG";
  EXPECT_EQ(row_bytes(c, frozen), 0u) << "nonlinear CG";
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
  // Its six vectors: four compact (3 a row of the evaluator's), p and K p
  // in the evaluator's own numbering (3 a particle of its room).
  const Evaluator& ev = freed.loop->evaluator();
  const size_t newton = (4 * 3 * ev.row_capacity() + 2 * 3 * ev.local_capacity()) * sizeof(double);
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


// The gathered level (K, right-hand side and result of every rank's rows)
// is held only by the multigrid on several ranks: on one rank it stays
// empty with either preconditioner, and nothing is gathered.
TEST(Memory, OneRankGathersNoLevel) {
  for (Preconditioner pc : {Preconditioner::Jacobi, Preconditioner::Multigrid}) {
    Scene s;
    s.cloth.particles = {33, 33};
    s.cloth.tile = 8;
    s.cloth.height = 0.401;  // contact within a few steps: Newton solves
    s.solver.method = SolverMethod::Newton;
    s.solver.preconditioner = pc;
    Simulation w(s, test_fabric());
    int solved = 0;
    for (int k = 0; k < 6; ++k) solved += w.step().iterations;
    EXPECT_GT(solved, 0);
    const NewtonSolver& newton = w.loop->newton();
    if (pc == Preconditioner::Multigrid) {
      EXPECT_GT(newton.multigrid_builds(), 0);
    }
    MemoryTable t;
    w.loop->memory(t);
    EXPECT_TRUE(listed(t, kGatheredLevel));
    EXPECT_EQ(row_bytes(t, kGatheredLevel), 0u);
    EXPECT_TRUE(listed(t, kGatheredVectors));
    EXPECT_EQ(row_bytes(t, kGatheredVectors), 0u);
    EXPECT_EQ(newton.multigrid_builds_bytes() + newton.multigrid_cycles_bytes(), 0);
    EXPECT_EQ(newton.multigrid_build_bytes() + newton.multigrid_cycle_bytes(), 0);
  }
}

// The rows find their elements by walking the lists beside the particles
// (no map by slot): every slot a particle gathers gets the position a plain
// search of its tile's part of the list (or of the ring) gives, -1 where
// there is none, whatever order the particles come in: list order (the
// walk's), backwards, and the hanging particles' order. On an AMRC mesh
// with coarse leaves, every other tile owned and the rest as the ring.
TEST(Evaluator, ListWalkFindsWhatASearchFinds) {
  Scene s;
  s.cloth.particles = {23, 19};
  s.cloth.size = {0.3, 0.25};
  s.cloth.tile = 5;
  Simulation w(s, test_fabric());
  Quadtree tree(23, 19, 2);
  const std::vector<double> flat(23 * 19, 0.0);
  for (int pass = 0; pass < 4; ++pass) adapt(tree, flat, 1.0, 0.5);
  tree.refine(tree.leaf_at(9, 5));
  w.set_tree(tree);
  w.rebuild();
  std::vector<int> owned;
  for (int t = 0; t < w.tiling.count(); t += 2) owned.push_back(t);
  std::vector<int64_t> ring;
  for (int64_t p = 0; p < w.cloth.grid.n(); ++p)
    if (w.tiling.tile_of(p) % 2 == 1) ring.push_back(p);
  ActiveLists lists;
  build_active_lists(w.cloth, w.tiling, owned, lists, ring);
  hanging_links(*w.tree(), lists.hanging);
  const Cloth& c = w.cloth;
  auto search = [&](int kind, int64_t s) -> int64_t {
    const ActiveList* own[3] = {&lists.edges, &lists.triples, &lists.shears};
    const ActiveList* rl[3] = {&lists.ring_edges, &lists.ring_triples, &lists.ring_shears};
    const auto& o = own[kind]->items;
    const auto& r = rl[kind]->items;
    if (auto f = std::find(o.begin(), o.end(), s); f != o.end()) return f - o.begin();
    if (auto f = std::find(r.begin(), r.end(), s); f != r.end()) return int64_t(o.size()) + (f - r.begin());
    return -1;
  };
  int found = 0, ringed = 0, missing = 0, wrong = 0;
  auto check = [&](ListWalk& walk, int64_t p) {
    auto ask = [&](int place, int kind, int64_t s) {
      const int64_t want = search(kind, s), got = walk.position(place, kind, s);
      wrong += got != want;
      found += want >= 0;
      ringed += want >= own_size(lists, kind);
      missing += want < 0;
    };
    for (int d = 0; d < 2; ++d) {
      const int64_t pv = c.prev_at(d, p), nx = c.next_at(d, p);
      ask(5 * d, 0, 2 * p + d);
      if (pv >= 0) ask(5 * d + 1, 0, 2 * pv + d);
      if (nx >= 0) ask(5 * d + 2, 1, 2 * nx + d);
      ask(5 * d + 3, 1, 2 * p + d);
      if (pv >= 0) ask(5 * d + 4, 1, 2 * pv + d);
    }
    ask(10, 2, p);
    for (int k = 0; k < 3; ++k)
      if (c.corner_of[k][p] >= 0) ask(11 + k, 2, c.corner_of[k][p]);
  };
  const auto& pl = lists.particles.items;
  ListWalk forward(lists, w.tiling), backward(lists, w.tiling), hanging(lists, w.tiling);
  for (int64_t p : pl) check(forward, p);
  for (auto p = pl.rbegin(); p != pl.rend(); ++p) check(backward, *p);
  for (const HangingLink& h : lists.hanging) check(hanging, h.h);
  std::printf("slots asked for: %d found (%d in the ring), %d in no list\n", found, ringed, missing);
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(found, 400) << "the test does not test";
  EXPECT_GT(ringed, 40) << "no slot in the ring";
  EXPECT_GT(missing, 40) << "no slot in no list";
  EXPECT_GT(lists.hanging.size(), 0u) << "no hanging particles";
}

}  // namespace
}  // namespace drape::test
