#pragma once
// The benchmarks' common state: a cloth of n x n denim-A particles mid-drape
// (positions jittered by a tenth of a spacing, tensions and moments spread
// over their bands), the same for a given seed in every run.
#include <random>

#include "io/kes.hpp"
#include "solver/world.hpp"

namespace drape {

inline Scene mid_drape_scene(int n, Schedule schedule = Schedule::ActiveLists) {
  Scene scene;
  scene.cloth.particles = {n, n};
  scene.parallel.schedule = schedule;
  return scene;
}

inline void jitter_mid_drape(World& w, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  const Layout& L = w.cloth.layout;
  for (int64_t k = 0; k < L.tension(); ++k) w.cloth.z[k] += 0.1 * w.cloth.grid.hi * u(rng);
  for (int64_t k = L.tension(); k < L.moment(); ++k) w.cloth.z[k] = 5.0 * (1 + u(rng));
  for (int64_t k = L.moment(); k < L.size(); ++k) w.cloth.z[k] = 1e-3 * u(rng);
  w.loop->freeze_bend_axes();
}

}  // namespace drape
