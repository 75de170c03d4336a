// Two ranks: each rank's evaluator holds the elements of its own tiles and
// of its ghost ring (its arrays in list order), not the grid's.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cstdio>

#include "decomp/decomposition.hpp"
#include "solver/memory_table.hpp"
#include "support/scenes.hpp"

namespace drape::test {
namespace {

size_t evaluator_bytes(TimeLoop& loop) {
  MemoryTable t;
  loop.evaluator().memory(t);
  return t.total();
}

// Half the tiles and a ring of one particle: well under two thirds of one
// rank's table (about 0.55 at 129 x 129; the grid-sized residual and slot
// maps are the rest). Arrays sized by the grid would give 1.
TEST(MemoryNp2, EvaluatorHoldsItsOwnTiles) {
  Scene s;
  s.cloth.particles = {129, 129};
  s.cloth.tile = 16;
  const Fabric f = test_fabric();
  Timers tm;
  Simulation one(s, f);
  one.loop->step(tm);
  const size_t whole = evaluator_bytes(*one.loop);

  Cloth cloth = make_cloth(s, f);
  Model model = make_model(s, f, cloth.grid.hi, cloth.grid.hj);
  const Tiling tiling(cloth.grid.ni, cloth.grid.nj, s.cloth.tile);
  const Decomposition dec = decompose(cloth, tiling, MPI_COMM_WORLD, ghost_widths(false, 0));
  ActiveLists lists;
  build_active_lists(cloth, tiling, dec.owned, lists, dec.halo->ring());
  const LoopPolicy policy{s.parallel.schedule, s.parallel.chunk};
  TimeLoop loop(cloth, model, lists, tiling, policy, *dec.reducer, s.solver, dec.ghosts());
  loop.step(tm);
  const size_t mine = evaluator_bytes(loop);
  std::printf("evaluator: %zu bytes on one rank, %zu on this one of two\n", whole, mine);
  EXPECT_LT(double(mine), 0.65 * double(whole));
}

}  // namespace
}  // namespace drape::test
