#pragma once
// Rigid obstacles (box, sphere, disc, floor) as a penalty force: a particle closer
// than the contact thickness delta to a surface is pushed out along n, with
// a force rising smoothly from zero at distance delta. Signed distance d, its gradient n and Hessian come from
// the obstacle's shape; the Newton cost needs all three.
#include <cmath>

#include "solver/scene.hpp"

namespace drape {

struct Obstacle {
  ObstacleShape shape = ObstacleShape::None;
  double center[3] = {0, 0, 0};
  double half[3] = {0, 0, 0};  // box half sizes
  double radius = 0;
  bool floor = false;
  double floor_z = 0;
};

struct Contact {
  Obstacle obstacle;
  double thickness = 1e-3;    // delta, m
  double stiffness = 1.0;     // k, N/m
  double friction = 0;        // Coulomb mu against the box or sphere
  double floor_friction = 0;  // Coulomb mu against the floor
  double slip = 1e-6;         // eps, m: the slip over which friction ramps up to mu N
  bool has_friction() const { return friction > 0 || floor_friction > 0; }
};

// Signed distance from x to the shape (negative inside), its gradient n
// (unit) and Hessian (3x3, row-major; null: not wanted).
double box_distance(const Obstacle& o, const double* x, double* n, double* hess);
double sphere_distance(const Obstacle& o, const double* x, double* n, double* hess);
// The disc: a vertical cylinder of radius o.radius and height 2 o.half[2]
// about o.center (flat top and bottom, a round rim).
double disc_distance(const Obstacle& o, const double* x, double* n, double* hess);
// Whichever of the three the obstacle is; 1e300 (far) without one.
double shape_distance(const Obstacle& o, const double* x, double* n, double* hess);
// Whether x lies beyond a layer about the shape, found without its distance:
// off one of a box's faces by at least the layer (the distance is then at
// least that face's gap: sqrt(fl(q^2)) is q exactly and further terms only
// add), so no penalty or hold of that layer acts and box_distance's square
// root and divisions need not run. Most of the cloth is away from the box.
// False where it cannot tell (inside that reach, or another shape).
inline bool beyond_layer(const Obstacle& o, const double* x, double layer) {
  if (o.shape != ObstacleShape::Box) return false;
  for (int k = 0; k < 3; ++k) {
    const double q = std::fabs(x[k] - o.center[k]) - o.half[k];
    if (q > 0 && q >= layer) return true;
  }
  return false;
}

// Penalty force on a particle at x. If jac_t_r is non-null, also adds
// -(dF/dx)^T r to it (the contact part of the Newton cost's gradient).
// If slope is non-null, adds d|F|/d(penetration) to it. Returns true when in contact.
bool contact_force(const Contact& c, const double* x, double* force, const double* r = nullptr,
                   double* jac_t_r = nullptr, double* slope = nullptr);

// Lagged Coulomb friction (src/solver/friction.cpp) on a particle at x
// whose step started at x1. Each surface it touched at x1 lends the normal
// force N and normal n it had there, both frozen for the step; the slip u is
// the part of x - x1 across n, and the force -mu N f(|u|) u/|u|, with
// f(s) = 2s/eps - (s/eps)^2 up to eps and 1 beyond (C1: the Newton residual
// stays smooth). Adds the force to `force` and, if jac_t_r is non-null,
// -(dF/dx)^T r to it. Nothing without friction.
void friction_force(const Contact& c, const double* x, const double* x1, double* force,
                    const double* r = nullptr, double* jac_t_r = nullptr);
// Adds -dF/dx (3x3, row-major, symmetric, positive semi-definite) to block;
// false (nothing added) where no surface holds the particle.
bool friction_block(const Contact& c, const double* x, const double* x1, double* block);
// The trace of friction_block's block (0 without one): diagonal estimates;
// held (if given) says whether a surface holds the particle (a block).
double friction_trace(const Contact& c, const double* x, const double* x1, bool* held = nullptr);
// The penalty force of a layer penetrated by pen (> 0) and its slope.
double penalty(const Contact& c, double pen, double* slope);

// Moves x out to distance `clearance` from every surface it is closer to.
// Returns true if it moved.
bool push_out(const Obstacle& o, double clearance, double* x);

// An inelastic contact for a particle found inside (the time step's safety
// net): x goes onto the surface of each shape it is inside, and its step dx
// loses the part into that surface. The push itself is not motion: counted
// as speed, a 2 mm push in a 0.2 ms step became 10 m/s thrown back in.
void settle_on_surface(const Obstacle& o, double* x, double* dx);

// Signed distance to the nearest surface of any shape (+inf without one).
double clearance(const Obstacle& o, const double* x);

// Deepest penetration below zero distance over all shapes (0 if outside all).
double penetration(const Obstacle& o, const double* x);

}  // namespace drape
