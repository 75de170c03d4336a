#pragma once
// A small drape onto a box (contact, the bands loading and reversing),
// Newton with the multigrid: the scene the Newton-step variants (line
// searches, the kinks' active set) are compared on, and a run of it counted.
#include <gtest/gtest.h>
#include <omp.h>

#include <functional>
#include <string>
#include <vector>

#include "scenes.hpp"
#include "solver/checksum.hpp"

namespace drape::test {

struct KinkDrapeOutcome {
  std::string checksum;
  int newton = 0, evaluations = 0, unconverged = 0, linear = 0;
};

// The 17 x 17 cloth dropped onto a 0.1 m box; with `fixed_dt`, every step
// 4 ms (so that variants cover the same simulated time whatever their
// iteration counts would make of dt).
inline Scene kink_drape_scene(bool fixed_dt) {
  Scene s;
  s.cloth.particles = {17, 17};
  s.cloth.size = {0.3, 0.3};
  s.cloth.tile = 5;
  s.cloth.height = 0.1 + 0.0094 + 0.0005;
  s.obstacle.center = {0.0, 0.0, 0.05};
  s.obstacle.size = {0.1, 0.1, 0.1};
  s.solver.dt = 4e-3;
  s.solver.dt_max = fixed_dt ? s.solver.dt : 0.02;
  if (fixed_dt) s.solver.dt_min = s.solver.dt;
  s.solver.drag = 10;
  s.solver.max_iterations = 300;
  s.solver.preconditioner = Preconditioner::Multigrid;
  return s;
}

// `steps` steps of scene s on `threads` threads: the Newton iterations,
// evaluations, linear iterations and unconverged steps summed, and the state's
// checksum; `on_step` (if given) sees each step's stats, steps counted from 1.
inline KinkDrapeOutcome run_kink_drape(const Scene& s, int threads, int steps,
                                       const std::function<void(int, const StepStats&)>& on_step = {}) {
  omp_set_num_threads(threads);
  Simulation w(s, test_fabric());
  KinkDrapeOutcome out;
  for (int k = 0; k < steps; ++k) {
    const StepStats st = w.step();
    if (on_step) on_step(k + 1, st);
    out.newton += st.newton_iterations;
    out.evaluations += st.evaluations;
    out.linear += st.iterations;
    out.unconverged += st.converged ? 0 : 1;
  }
  std::vector<int> all;
  for (int t = 0; t < w.tiling.count(); ++t) all.push_back(t);
  out.checksum = state_checksum(w.cloth, w.tiling, all, w.red()).hex();
  return out;
}

// `run(threads)` on one thread and on two: the same state bit for bit, the
// same counts, and no step left unconverged.
inline void expect_one_and_two_threads_agree(const std::function<KinkDrapeOutcome(int threads)>& run) {
  const KinkDrapeOutcome one = run(1), two = run(2);
  EXPECT_EQ(one.checksum, two.checksum);
  EXPECT_EQ(one.newton, two.newton);
  EXPECT_EQ(one.evaluations, two.evaluations);
  EXPECT_EQ(one.unconverged, 0);
}

}  // namespace drape::test
