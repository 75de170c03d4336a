// No heap allocation during time steps once a run has started, AMRC on:
// every operator new is counted while steps run and the mesh adapts.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "amrc/amrc.hpp"
#include "amrc/remesh.hpp"
#include "support/folded_strip.hpp"
#include "support/scenes.hpp"

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
}  // namespace

void* operator new(std::size_t n) {
  if (g_counting) ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace drape::test {
namespace {

void expect_no_allocation(bool slope_line_search, bool band_active_set = false, bool self_contact = false) {
  Scene s;  // the box scene, small
  s.cloth.particles = {33, 33};
  s.solver.self_contact = self_contact;
  s.solver.slope_line_search = slope_line_search;
  s.solver.band_active_set = band_active_set;
  s.solver.preconditioner = Preconditioner::Jacobi;  // what `auto` takes with AMRC
  s.cloth.tile = 8;
  s.cloth.height = 0.42;
  Simulation w(s, test_fabric());
  Amrc amrc(w.cloth, 2, self_contact);
  std::vector<int> all(w.tiling.count());
  for (int t = 0; t < w.tiling.count(); ++t) all[t] = t;
  w.lists.hanging.reserve(w.cloth.grid.n());
  auto rebuild = [&] {
    build_active_lists(w.cloth, w.tiling, all, w.lists);
    hanging_links(amrc.tree(), w.lists.hanging);
    w.loop->mesh_changed();
  };
  amrc.apply(w.cloth, w.fabric.density, s.cloth.shear);
  rebuild();
  int changes = 0, iterations = 0;
  auto run = [&](int steps) {
    for (int k = 0; k < steps; ++k) {
      iterations += w.step().iterations;
      Thresholds th{0.1, 0.02};
      th.pair_distance = self_contact ? 2 * w.model.contact.thickness : 0.0;  // the near mask too
      const AdaptStats a = amrc.adapt(w.cloth, w.fabric.density, s.cloth.shear, th);
      if (a.refined + a.coarsened > 0) {
        rebuild();
        ++changes;
      }
    }
  };
  run(3);  // the first steps size every buffer and start OpenMP's threads
  changes = iterations = 0;
  g_counting = true;
  run(25);
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0) << "heap allocations during 25 steps";
  EXPECT_GT(changes, 0) << "the mesh should have adapted while counting";
  EXPECT_GT(iterations, 0) << "the solver should have worked while counting";
}

TEST(Allocation, NoneDuringTimeStepsWithAmrc) { expect_no_allocation(false); }

TEST(Allocation, NoneWithNewtonsSlopeLineSearch) { expect_no_allocation(true); }

TEST(Allocation, NoneWithNewtonsBandActiveSet) { expect_no_allocation(false, true); }

// AMRC with self-contact: the near mask's positions and hash, and the pair
// list built again at each new mesh.
TEST(Allocation, NoneDuringTimeStepsWithAmrcAndSelfContact) { expect_no_allocation(false, false, true); }

// Self-contact on one rank: the folded strip's flap dropped onto its lower
// half from 2.4 pair distances, pair lists built again between Newton steps
// as it falls (their partners' indices kept again) while counting. `falls`
// before counting: the steps of a whole fall, the flap then lifted again.
void expect_no_allocation_with_pairs(Preconditioner pc, int falls = 0) {
  Scene s = strip_scene(true);
  s.solver.preconditioner = pc;
  Simulation w(s, test_fabric());
  fold(w, 2.4);
  const SelfContact& sc = w.loop->evaluator().self_contact();
  for (int k = 0; k < 3; ++k) w.step();  // sizes every buffer, the pair list's included
  for (int f = 0; f < falls; ++f) {
    for (int k = 0; k < 40; ++k) w.step();  // landed: 864 pairs listed after 32 steps
    fold(w, 2.4);
  }
  const uint64_t built = sc.builds();
  int iterations = 0;
  g_allocations = 0;
  g_counting = true;
  for (int k = 0; k < 60; ++k) iterations += w.step().iterations;
  g_counting = false;
  EXPECT_EQ(g_allocations.load(), 0) << "heap allocations during 60 steps";
  EXPECT_GT(sc.builds(), built) << "the pair list should have been built again while counting";
  EXPECT_GT(sc.listed(), 0) << "no pairs listed";
  EXPECT_GT(iterations, 0);
}

TEST(Allocation, NoneWithSelfContact) { expect_no_allocation_with_pairs(Preconditioner::Jacobi); }

// The same with the multigrid: K's pattern, the levels' products and the
// coarsest level's ordering and factors set again each time the pair list
// is built again, the levels' prolongations kept. Counted over a second
// fall: K's and the products' patterns grow with the pair list (grow-only,
// as the pair list's own arrays past their reserve) through the first, from
// no pairs to 864, in 15 allocations; the second reuses them up to 1086.
TEST(Allocation, NoneWithSelfContactAndMultigrid) { expect_no_allocation_with_pairs(Preconditioner::Multigrid, 1); }

}  // namespace
}  // namespace drape::test
