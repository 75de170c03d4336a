// The arrays a run holds, owner by owner, in bytes a particle of the grid:
// the box drape on the finest mesh of n x n particles, after a few steps
// (the solvers size their vectors at their first solve). The table in
// docs/performance.md ("Memory") comes from here; the peak RSS beside it
// is this process's. With --level L, the steps run on grid sequencing's
// uniform level L instead (the arrays sized by the lists hold its elements).
#include <sys/resource.h>

#include <CLI/CLI.hpp>

#include <cstdio>
#include <memory>
#include <string>

#include "amrc/amrc.hpp"
#include "io/kes.hpp"
#include "app/simulation.hpp"

int main(int argc, char** argv) {
  using namespace drape;
  CLI::App app("drape's arrays, bytes per particle");
  int n = 1000, steps = 2, level = 0;
  std::string method = "newton";
  app.add_option("--size", n, "particles per side")->check(CLI::Range(3, 20000));
  app.add_option("--steps", steps, "time steps before the table")->check(CLI::Range(0, 1000));
  app.add_option("--method", method, "newton or cg")->check(CLI::IsMember({"newton", "cg"}));
  app.add_option("--level", level, "grid sequencing's uniform level (0: the finest mesh)")->check(CLI::Range(0, 12));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  Scene scene;
  scene.cloth.particles = {n, n};
  scene.solver.method = method == "cg" ? SolverMethod::Cg : SolverMethod::Newton;
  Simulation w(scene, load_fabric(scene.cloth.fabric));
  std::unique_ptr<Amrc> amrc;
  if (level > 0) {  // a new stage, as the drape program starts one
    amrc = std::make_unique<Amrc>(w.cloth, level);
    amrc->set_uniform_level(w.cloth, w.fabric.density, scene.cloth.shear, level);
    std::vector<int> all(w.tiling.count());
    for (int t = 0; t < w.tiling.count(); ++t) all[t] = t;
    w.lists = ActiveLists{};  // the finest mesh's capacity gone: the program builds the stage's first
    build_active_lists(w.cloth, w.tiling, all, w.lists);
    w.loop->mesh_changed(true);
  }
  for (int k = 0; k < steps; ++k) w.step();
  MemoryTable t;
  add_memory(t, w.cloth);
  add_memory(t, w.lists);
  w.loop->memory(t);
  if (amrc) amrc->memory(t);  // the tree and its fields: the stage's too
  const double per = 1.0 / double(w.cloth.grid.n());
  std::printf("| owner | arrays | bytes a particle |\n|---|---|---:|\n");
  for (const MemoryTable::Row& r : t.rows)
    if (r.bytes > 0) std::printf("| %s | %s | %.1f |\n", r.owner.c_str(), r.array.c_str(), double(r.bytes) * per);
  std::printf("| all | | %.1f |\n", double(t.total()) * per);
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  std::printf("\n%d x %d, %d step(s), %s: peak RSS %.1f MB, %.0f bytes a particle\n", n, n, steps, method.c_str(),
              1e-6 * 1024.0 * double(u.ru_maxrss), 1024.0 * double(u.ru_maxrss) * per);
  if (level > 0) std::printf("(on level %d; the peak counts the finest mesh's evaluator, built first)\n", level);
  return 0;
}
