#pragma once
// Rigid obstacles (box, sphere, floor) as a penalty force: a particle closer
// than the contact thickness delta to a surface is pushed out along n, with
// a force rising smoothly from zero at distance delta. Signed distance d, its gradient n and Hessian come from
// the obstacle's shape; the Newton cost needs all three.
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
  double thickness = 1e-3;  // delta, m
  double stiffness = 1.0;   // k, N/m
};

// Signed distance from x to the shape (negative inside), its gradient n
// (unit) and Hessian (3x3, row-major; null: not wanted).
double box_distance(const Obstacle& o, const double* x, double* n, double* hess);
double sphere_distance(const Obstacle& o, const double* x, double* n, double* hess);

// Penalty force on a particle at x. If jac_t_r is non-null, also adds
// -(dF/dx)^T r to it (the contact part of the Newton cost's gradient).
// If slope is non-null, adds d|F|/d(penetration) to it. Returns true when in contact.
bool contact_force(const Contact& c, const double* x, double* force, const double* r = nullptr,
                   double* jac_t_r = nullptr, double* slope = nullptr);

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
