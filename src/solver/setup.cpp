// Building the cloth and the model of a scene: the finest mesh, every
// particle active, flat at the scene's height, released from rest.
#include <algorithm>
#include <cmath>
#include <vector>

#include "mesh/active_lists.hpp"
#include "mesh/topology.hpp"
#include "solver/model.hpp"

namespace drape {

double Cloth::total_mass() const {
  double m = 0;
  for (double v : mass) m += v;
  return m;
}

double total_mass(const Cloth& c, const Tiling& tl, const std::vector<int>& owned, const Reducer& red) {
  std::vector<double> part(owned.size(), 0.0);
  for (size_t k = 0; k < owned.size(); ++k) {
    const TileRange r = tl.range(owned[k]);
    for (int i = r.i0; i < r.i1; ++i)
      for (int j = r.j0; j < r.j1; ++j) part[k] += c.mass_at(c.grid.id(i, j));
  }
  double m = 0;
  red.sum_tiles(owned, part.data(), 1, &m);
  return m;
}

// Contact acts within delta of a surface (half the mesh spacing, or half the
// thickness if larger); a push of delta balances 10^4 weights of the mesh's
// particles, so they settle well within delta and never reach the surface.
// A coarse mesh (filled = true) stands for the finest one written between its
// particles: the bilinear patch of a cell over an obstacle's corner clears it
// only if the layer is about half the cell's diagonal, so that is its layer.
void set_contact_layer(Contact& c, const Scene& scene, const Fabric& fabric, double hi, double hj, double g,
                       bool filled) {
  const double weight = fabric.density * hi * hj * g;
  const double reach = filled ? std::hypot(hi, hj) : std::min(hi, hj);
  const double delta = scene.solver.contact_thickness > 0 ? scene.solver.contact_thickness
                                                          : std::max(0.5 * reach, 0.5 * fabric.thickness);
  c.thickness = delta;
  c.stiffness = 1e4 * weight / delta;
}

Model make_model(const Scene& scene, const Fabric& fabric, double hi, double hj) {
  Model m;
  for (int d = 0; d < 2; ++d) {
    m.stretch[d] = Band::tensile(fabric.tensile[d], scene.cloth.compression);
    const BendingKES& b = fabric.bending[d];
    m.bend[d] = Band::linear(b.b, b.hb, b.load, b.unload);
  }
  const ShearKES& s = fabric.shear;
  m.shear = Band::linear(s.g, s.hg, s.load, s.unload);
  m.use_shear = scene.cloth.shear;
  for (int d = 0; d < 2; ++d) {
    m.bend[d].set_reversal(scene.cloth.bend_reversal);
    m.stretch[d].set_reversal(scene.cloth.stretch_reversal);
  }
  m.shear.set_reversal(scene.cloth.shear_reversal);
  // Residual forces are measured in the weight of one finest-mesh particle.
  const double g = std::fabs(m.gravity[2]);
  const double weight = fabric.density * hi * hj * g;
  m.force_scale = weight;
  Obstacle& o = m.contact.obstacle;
  const ObstacleSpec& os = scene.obstacle;
  o.shape = os.shape;
  for (int k = 0; k < 3; ++k) {
    o.center[k] = os.center[k];
    o.half[k] = 0.5 * os.size[k];
  }
  o.radius = os.radius;
  o.floor = os.floor;
  o.floor_z = 0.0;
  m.contact.friction = os.friction;
  m.contact.floor_friction = os.floor_friction;
  set_contact_layer(m.contact, scene, fabric, hi, hj, g, false);
  m.dt = m.dt_prev = scene.solver.dt;
  m.memory = scene.solver.memory;
  m.drag = scene.solver.drag;
  m.self_contact = scene.solver.self_contact;
  return m;
}

namespace {
// The Cusick specimen: a cell of the grid stays where its centre lies
// within the disc inscribed in the cloth (radius size/2 about its centre),
// and a particle where it is a corner of such a cell; the others are
// removed before any topology is built, so no edge, triple or cell touches
// them. The outline is the cells' staircase, whose area is the disc's
// within a few per mille on a 65 x 65 grid (cells wholly inside would
// miss a strip half a cell wide: 4 % less).
void cut_to_disc(Cloth& c, const ClothSpec& spec) {
  const Grid& g = c.grid;
  const double r = 0.5 * spec.size[0];
  std::vector<uint8_t> keep(g.n(), 0);
  for (int i = 0; i + 1 < g.ni; ++i)
    for (int j = 0; j + 1 < g.nj; ++j) {
      const double dx = (i + 0.5) * g.hi - 0.5 * spec.size[0], dy = (j + 0.5) * g.hj - 0.5 * spec.size[1];
      if (dx * dx + dy * dy > r * r) continue;
      for (int64_t q : {g.id(i, j), g.id(i + 1, j), g.id(i, j + 1), g.id(i + 1, j + 1)}) keep[q] = 1;
    }
  for (int64_t p = 0; p < g.n(); ++p)
    if (!keep[p]) c.flags[p] = kRemoved;
}
}  // namespace

Cloth make_cloth(const Scene& scene, const Fabric& fabric) { return make_cloth(scene, fabric, nullptr); }

Cloth make_cloth(const Scene& scene, const Fabric& fabric, const std::vector<int64_t>* held) {
  Cloth c;
  Grid& g = c.grid;
  g.ni = scene.cloth.particles[0];
  g.nj = scene.cloth.particles[1];
  g.hi = scene.cloth.size[0] / (g.ni - 1);
  g.hj = scene.cloth.size[1] / (g.nj - 1);
  const int64_t n = g.n();
  c.layout.n = n;
  c.layout.m = held ? hold_slots(c, *held) : n;
  const size_t m = size_t(c.layout.m);
  c.z.assign(c.layout.size(), 0.0);
  c.x1.assign(3 * m, 0.0);
  c.x2.assign(3 * m, 0.0);
  c.mass.assign(m, 0.0);  // every particle, at its grid id, until hold_particles (held: in slots)
  c.flags.assign(n, kActive);
  c.level.assign(n, 0);
  for (int k = 0; k < 3; ++k) {
    c.cell[k].assign(m, -1);
    c.corner_of[k].assign(m, -1);
  }
  const double dt = scene.solver.dt, gz = -9.80665;
  double* x = c.x();
#pragma omp parallel for schedule(static)
  for (int i = 0; i < g.ni; ++i)
    for (int j = 0; j < g.nj; ++j) {
      const int64_t p = g.id(i, j);
      x[3 * p + 0] = scene.cloth.center[0] + i * g.hi - 0.5 * scene.cloth.size[0];
      x[3 * p + 1] = scene.cloth.center[1] + j * g.hj - 0.5 * scene.cloth.size[1];
      x[3 * p + 2] = scene.cloth.height;
      const bool fixed = i < scene.cloth.clamp;  // on the platform: held, at rest
      if (fixed) c.flags[p] |= kFixed;
      if (!c.holds(p)) continue;
      double *x1 = c.x1_at(p), *x2 = c.x2_at(p);
      for (int k = 0; k < 3; ++k) x1[k] = x2[k] = x[3 * p + k];
      // Released from rest under gravity: x(-dt) = x(0) + g dt^2 / 2 makes the
      // three-point acceleration exact for a free fall.
      if (!fixed) x2[2] += 0.5 * gz * dt * dt;
    }
  c.dt = c.dt_prev = dt;
  if (scene.cloth.shape == ClothShape::Disc) cut_to_disc(c, scene.cloth);
  rebuild_topology(c, scene.cloth.shear);
  rebuild_geometry(c, fabric.density);
  return c;
}

}  // namespace drape
