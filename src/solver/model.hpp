#pragma once
// Everything the cost needs besides the cloth's arrays: KES bands per
// direction, gravity, contact, the time step, and the scales that make the
// cost terms comparable (docs/design.md §1, §6).
#include "solver/band.hpp"
#include "solver/reducer.hpp"
#include "mesh/cloth.hpp"
#include "solver/contact.hpp"
#include "solver/fabric.hpp"
#include "solver/scene.hpp"

namespace drape {

struct Model {
  Band stretch[2];  // tension (N/m) against strain, warp and weft
  Band bend[2];     // moment (N*m/m) against curvature (1/m)
  Band shear;       // shear force (N/m) against shear angle (rad)
  double gravity[3] = {0, 0, -9.80665};
  Contact contact;
  double dt = 1e-3, dt_prev = 1e-3;  // this step and the previous one, s
  double force_scale = 1;            // F0: residual forces are measured in F0 (a particle's weight)
  double memory = 1.0;               // weight of the force memory term
  double drag = 0.0;                 // 1/s: air drag, a force -drag*m*v on each particle
  bool self_contact = false;         // cloth-cloth contact (solver/self_contact.hpp)
  // Term switches (tests check each term's gradient alone).
  bool use_newton = true, use_stretch = true, use_bend = true, use_shear = true;

  // d(acceleration)/dx for the three-point formula with unequal steps.
  double accel_coeff() const { return 2.0 / ((dt + dt_prev) * dt); }
  // d(residual)/dx per unit mass: inertia and drag (v = (x - x1)/dt).
  double inertia_coeff() const { return accel_coeff() + drag / dt; }
};

struct Cloth;
struct Scene;

// Builds the model of a scene and fabric for a grid of spacing h.
Model make_model(const Scene& scene, const Fabric& fabric, double hi, double hj);
// The contact layer (thickness and stiffness) of a mesh with spacings hi, hj
// under gravity g (m/s^2); `filled`: a coarse mesh whose finer particles are
// filled in between its own when written.
void set_contact_layer(Contact& c, const Scene& scene, const Fabric& fabric, double hi, double hj, double g,
                       bool filled);

// A flat cloth at rest at the scene's height, on the finest mesh, every
// particle active, nothing clamped. Allocates every array once.
Cloth make_cloth(const Scene& scene, const Fabric& fabric);
// The same cloth with the step history, forces, masses, neighbour tables,
// cells and switches of the particles `held` (ascending grid ids) only, in
// slots (hold_particles' layout) from the start: no array of them is ever
// the grid's. Their values are the whole cloth's, bit for bit.
Cloth make_cloth(const Scene& scene, const Fabric& fabric, const std::vector<int64_t>* held);
// The cloth's mass, summed by tile over the owned tiles' particles (a rank
// holds only its tiles' and ghosts' masses): the same bits on any ranks.
double total_mass(const Cloth& c, const Tiling& tl, const std::vector<int>& owned, const Reducer& red);

}  // namespace drape
