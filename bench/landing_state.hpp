#pragma once
// The linear-solve benchmarks' common state: the box drape on its finest
// mesh, stepped with Jacobi at a fixed dt to just after landing (contact
// active), and a per-call timer in the calling thread's CPU seconds (the
// machine may be shared).
#include <time.h>

#include "io/kes.hpp"
#include "app/simulation.hpp"

namespace drape {

inline Scene landing_scene(int n, double dt) {
  Scene scene;
  scene.cloth.particles = {n, n};
  scene.amrc.start_spacing = 0;
  scene.solver.dt = scene.solver.dt_min = scene.solver.dt_max = dt;
  scene.solver.preconditioner = Preconditioner::Jacobi;
  // Frictionless, as the linear solves' documented figures were measured.
  scene.obstacle.friction = scene.obstacle.floor_friction = 0;
  return scene;
}

// Steps w to `time` (s).
inline void step_to(Simulation& w, double time) {
  while (w.cloth.time < time - 0.5 * w.scene.solver.dt) w.step();
}

inline double cpu_seconds() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// CPU seconds per call, by repetition for about 0.2 s.
template <class F>
double per_call(F&& f) {
  f();
  int reps = 0;
  const double t0 = cpu_seconds();
  double t = t0;
  while (t - t0 < 0.2) {
    f();
    ++reps;
    t = cpu_seconds();
  }
  return (t - t0) / reps;
}

}  // namespace drape
