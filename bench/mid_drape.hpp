#pragma once
// The benchmarks' common state: a cloth of n x n denim-A particles mid-drape
// (positions jittered by a tenth of a spacing, tensions and moments spread
// over their bands), the same for a given seed in every run.
#include <random>

#include "amrc/criterion.hpp"
#include "io/kes.hpp"
#include "app/simulation.hpp"

namespace drape {

inline Scene mid_drape_scene(int n, Schedule schedule = Schedule::ActiveLists) {
  Scene scene;
  scene.cloth.particles = {n, n};
  scene.parallel.schedule = schedule;
  // Frictionless, as the scaling figures were measured.
  scene.obstacle.friction = scene.obstacle.floor_friction = 0;
  return scene;
}

// An uneven AMRC mesh like a drape's: coarse (leaves of 4 intervals) except
// a band at the finest level along a fold across the cloth's third, so that
// tiles carry very different work.
inline void uneven_amrc_mesh(Simulation& w) {
  const int n = w.cloth.grid.ni, m = w.cloth.grid.nj;
  Quadtree t(n, m, 2);
  const std::vector<double> flat(size_t(n) * m, 0.0), none;
  for (int pass = 0; pass < 3; ++pass) adapt(t, flat, 1.0, 0.5);
  std::vector<double> fold(size_t(n) * m, 0.0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j)
      if (std::abs(i - n / 3) <= n / 20) fold[size_t(i) * m + j] = 1.0;
  for (int pass = 0; pass < 3; ++pass) adapt(t, fold, 0.5, 0.1);
  w.set_tree(t);
  w.rebuild();
}

inline void jitter_mid_drape(Simulation& w, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  const Layout& L = w.cloth.layout;
  for (int64_t k = 0; k < L.tension(); ++k) w.cloth.z[k] += 0.1 * w.cloth.grid.hi * u(rng);
  for (int64_t k = L.tension(); k < L.moment(); ++k) w.cloth.z[k] = 5.0 * (1 + u(rng));
  for (int64_t k = L.moment(); k < L.size(); ++k) w.cloth.z[k] = 1e-3 * u(rng);
  w.loop->freeze_bend_axes();
}

}  // namespace drape
