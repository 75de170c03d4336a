// Two ranks: each rank's evaluator holds the elements of its own tiles and
// of its ghost ring (its arrays in list order), not the grid's.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cstdio>

#include "decomp/decomposition.hpp"
#include "solver/memory_table.hpp"
#include "support/memory_rows.hpp"
#include "support/scenes.hpp"

namespace drape::test {
namespace {

size_t evaluator_bytes(TimeLoop& loop) {
  MemoryTable t;
  loop.evaluator().memory(t);
  return t.total();
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

  Cloth cloth = make_cloth(s, f);
  Model model = make_model(s, f, cloth.grid.hi, cloth.grid.hj);
  const Tiling tiling(cloth.grid.ni, cloth.grid.nj, s.cloth.tile);
  const Decomposition dec = decompose(cloth, tiling, MPI_COMM_WORLD, ghost_widths(false, 0));
  ActiveLists lists;
  build_active_lists(cloth, tiling, dec.owned, lists, dec.halo->ring());
  const LoopPolicy policy{s.parallel.schedule, s.parallel.chunk};
  TimeLoop loop(cloth, model, lists, tiling, policy, *dec.reducer, s.solver, dec.ghosts());
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
}

}  // namespace
}  // namespace drape::test
