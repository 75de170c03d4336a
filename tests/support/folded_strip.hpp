#pragma once
// A strip folded across j onto itself (self-contact's scene): flat on the
// floor's layer, a half turn, and a flap back above the lower half.
#include <cmath>

#include "scenes.hpp"

namespace drape::test {

constexpr int kNi = 7, kNj = 23;
constexpr double kH = 0.01;  // spacing: the contact layer is h/2, the pair distance h

// Particle (i, j) of a strip folded across j: the grid line along j runs
// flat on the floor's layer for s < s0 (flat_in_h spacings), turns up a half
// circle of radius r, and runs back above the lower half at height 2r, a gap
// of gap_in_h spacings.
inline void fold(Simulation& w, double gap_in_h, double flat_in_h = 10) {
  const Grid& g = w.cloth.grid;
  const double layer = w.model.contact.thickness, r = 0.5 * gap_in_h * g.hj, s0 = flat_in_h * g.hj;
  for (int i = 0; i < g.ni; ++i)
    for (int j = 0; j < g.nj; ++j) {
      const double s = j * g.hj;
      double y, z;
      if (s <= s0) {
        y = s, z = 0;
      } else if (s <= s0 + M_PI * r) {
        const double a = (s - s0) / r;
        y = s0 + r * std::sin(a), z = r * (1 - std::cos(a));
      } else {
        y = s0 - (s - s0 - M_PI * r), z = 2 * r;
      }
      double* x = &w.cloth.z[3 * g.id(i, j)];
      x[0] = i * g.hi, x[1] = y, x[2] = 0.99 * layer + z;
    }
  Cloth& c = w.cloth;
  for (int64_t p = 0; p < g.n(); ++p)  // the history this rank holds (Cloth::slots)
    if (c.holds(p))
      for (int k = 0; k < 3; ++k) c.x1_at(p)[k] = c.x2_at(p)[k] = c.z[3 * p + k];
}

// With amrc, leaves up to 4 spacings wide (the flap and the lower half
// start on them, 4 times the pair distance between particles).
inline Scene strip_scene(bool self_contact, bool amrc = false) {
  Scene s = flat_scene(kNi, kNj, (kNi - 1) * kH, (kNj - 1) * kH);
  s.obstacle.floor = true;
  s.solver.self_contact = self_contact;
  s.solver.dt = 1e-3;
  s.solver.dt_max = 2e-3;
  s.solver.tolerance = 1e-8;
  s.solver.max_iterations = 400;
  s.solver.drag = 5;  // settles in a few tenths of a second
  s.amrc.enabled = amrc;
  s.amrc.max_level = 2;
  s.amrc.start_spacing = 4 * kH;
  return s;
}

// A 33 x 33 sheet for AMRC (to fold at 16 spacings): it starts on leaves 4
// spacings wide, which the first adaptations split where the flap faces the
// lower half.
inline Scene wide_strip_scene(bool self_contact) {
  Scene s = strip_scene(self_contact, true);
  s.cloth.particles = {33, 33};
  s.cloth.size = {32 * kH, 32 * kH};
  return s;
}

// The drape program's loop until `end` (s): steps, and AMRC's adaptations
// every amrc.every steps where it is on. Returns whether every step converged.
inline bool run_until(Simulation& w, double end) {
  bool converged = true;
  while (w.cloth.time < end) {
    const StepStats st = w.step();
    converged &= st.converged;
    if (w.scene.amrc.enabled && st.step % w.scene.amrc.every == 0) w.adapt();
  }
  return converged;
}

}  // namespace drape::test
