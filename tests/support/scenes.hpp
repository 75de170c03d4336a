#pragma once
// Scenes, a tree and a fabric for solver tests, built into a drape::Simulation.
#include <cmath>
#include <random>

#include "amrc/criterion.hpp"
#include "amrc/remesh.hpp"
#include "app/simulation.hpp"
#include "mesh/topology.hpp"

namespace drape::test {

// A scene with no obstacle: n x n particles of spacing h, flat at height z.
// Frictionless, so that a test adding a floor or a sphere measures what it
// names; the tests of friction turn it on themselves.
inline Scene flat_scene(int ni, int nj, double size_i, double size_j) {
  Scene s;
  s.cloth.particles = {ni, nj};
  s.cloth.size = {size_i, size_j};
  s.cloth.tile = 4;
  s.obstacle.shape = ObstacleShape::None;
  s.obstacle.floor = false;
  s.obstacle.friction = 0;
  s.obstacle.floor_friction = 0;
  return s;
}

// A 13 x 11 quadtree with leaves of levels 0 to 2 and hanging particles
// between them (some on sides clipped at the far border).
inline Quadtree mixed_tree() {
  Quadtree t(13, 11, 2);
  const std::vector<double> flat(13 * 11, 0.0);
  for (int pass = 0; pass < 4; ++pass) adapt(t, flat, 1.0, 0.5);
  t.refine(t.leaf_at(5, 4));
  t.refine(t.leaf_at(4, 4));
  return t;
}

// A denim-like fabric (KES denim A values in SI) that needs no data file.
inline Fabric test_fabric() {
  Fabric f;
  f.name = "test-denim";
  f.density = 0.3;
  f.thickness = 1.0e-3;
  for (int d = 0; d < 2; ++d) {
    f.tensile[d].emt = 0.055;
    f.tensile[d].lt = 0.71;
    f.tensile[d].rt = 0.54;
    f.tensile[d].fm = 490.3;
    f.bending[d].b = 0.172 * 9.807e-5;
    f.bending[d].hb = 0.5 * 0.139 * 9.807e-3;
  }
  f.shear.g = 2.18 * 0.9807 * 180 / M_PI;
  f.shear.hg = 0.5 * 5.0 * 0.9807;
  return f;
}

}  // namespace drape::test
