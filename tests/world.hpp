#pragma once
// A small simulated world for solver tests: cloth, model, tiles, lists,
// evaluator and time loop for a scene and a fabric, all on one rank.
#include <memory>
#include <random>

#include "amrc/active_lists.hpp"
#include "solver/model.hpp"
#include "solver/time_loop.hpp"

namespace drape::test {

struct World {
  Scene scene;
  Fabric fabric;
  Cloth cloth;
  Model model;
  Tiling tiling;
  ActiveLists lists;
  LocalReducer red;
  LoopPolicy policy;
  std::unique_ptr<TimeLoop> loop;

  World(const Scene& s, const Fabric& f) : scene(s), fabric(f) {
    cloth = make_cloth(scene, fabric);
    model = make_model(scene, fabric, cloth.grid.hi, cloth.grid.hj);
    rebuild();
  }
  // After changing flags (fixing particles) or the policy.
  void rebuild() {
    rebuild_topology(cloth, scene.cloth.shear);
    rebuild_geometry(cloth, fabric.density);
    tiling = Tiling(cloth.grid.ni, cloth.grid.nj, scene.cloth.tile);
    std::vector<int> owned;
    for (int t = 0; t < tiling.count(); ++t) owned.push_back(t);
    build_active_lists(cloth, tiling, owned, lists);
    policy = LoopPolicy{scene.parallel.schedule, scene.parallel.chunk};
    loop = std::make_unique<TimeLoop>(cloth, model, lists, tiling, policy, red, scene.solver);
  }
};

// A scene with no obstacle: n x n particles of spacing h, flat at height z.
inline Scene flat_scene(int ni, int nj, double size_i, double size_j) {
  Scene s;
  s.cloth.particles = {ni, nj};
  s.cloth.size = {size_i, size_j};
  s.cloth.tile = 4;
  s.obstacle.shape = ObstacleShape::None;
  s.obstacle.floor = false;
  return s;
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
