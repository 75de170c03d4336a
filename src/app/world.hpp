#pragma once
// One rank's whole simulation for a scene: cloth, model, tiles, active lists
// and time loop, every tile owned. Tests, benchmarks and tools build on it;
// the drape program assembles the same pieces itself, timing each phase.
#include <memory>
#include <optional>
#include <vector>

#include "mesh/active_lists.hpp"
#include "mesh/topology.hpp"
#include "amrc/remesh.hpp"
#include "solver/model.hpp"
#include "solver/time_loop.hpp"

namespace drape {

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
  std::optional<Quadtree> tree;  // AMRC's mesh; none: the finest grid

  World(const Scene& s, const Fabric& f) : scene(s), fabric(f) {
    cloth = make_cloth(scene, fabric);
    model = make_model(scene, fabric, cloth.grid.hi, cloth.grid.hj);
    rebuild();
  }
  // After changing flags (fixing particles), the tree or the policy.
  void rebuild() {
    if (tree) {
      apply_tree(*tree, cloth, fabric.density, scene.cloth.shear);
    } else {
      rebuild_topology(cloth, scene.cloth.shear);
      rebuild_geometry(cloth, fabric.density);
    }
    tiling = Tiling(cloth.grid.ni, cloth.grid.nj, scene.cloth.tile);
    std::vector<int> owned;
    for (int t = 0; t < tiling.count(); ++t) owned.push_back(t);
    build_active_lists(cloth, tiling, owned, lists);
    if (tree) hanging_links(*tree, lists.hanging);
    policy = LoopPolicy{scene.parallel.schedule, scene.parallel.chunk};
    loop = std::make_unique<TimeLoop>(cloth, model, lists, tiling, policy, red, scene.solver);
  }
};

}  // namespace drape
