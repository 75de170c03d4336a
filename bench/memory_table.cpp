// The arrays a run holds, owner by owner, in bytes a particle of the grid:
// the box drape on the finest mesh of n x n particles, after a few steps
// (the solvers size their vectors at their first solve). The table in
// docs/performance.md ("Memory") comes from here; the peak RSS beside it
// is this process's.
#include <sys/resource.h>

#include <CLI/CLI.hpp>

#include <cstdio>
#include <string>

#include "amrc/amrc.hpp"
#include "io/kes.hpp"
#include "app/world.hpp"

int main(int argc, char** argv) {
  using namespace drape;
  CLI::App app("drape's arrays, bytes per particle");
  int n = 1000, steps = 2;
  std::string method = "newton";
  app.add_option("--size", n, "particles per side")->check(CLI::Range(3, 20000));
  app.add_option("--steps", steps, "time steps before the table")->check(CLI::Range(0, 1000));
  app.add_option("--method", method, "newton or cg")->check(CLI::IsMember({"newton", "cg"}));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  Scene scene;
  scene.cloth.particles = {n, n};
  scene.solver.method = method == "cg" ? SolverMethod::Cg : SolverMethod::Newton;
  World w(scene, load_fabric(scene.cloth.fabric));
  Timers tm;
  for (int k = 0; k < steps; ++k) w.loop->step(tm);
  MemoryTable t;
  add_memory(t, w.cloth);
  add_memory(t, w.lists);
  w.loop->memory(t);
  const double per = 1.0 / double(w.cloth.grid.n());
  std::printf("| owner | arrays | bytes a particle |\n|---|---|---:|\n");
  for (const MemoryTable::Row& r : t.rows)
    if (r.bytes > 0) std::printf("| %s | %s | %.1f |\n", r.owner.c_str(), r.array.c_str(), double(r.bytes) * per);
  std::printf("| all | | %.1f |\n", double(t.total()) * per);
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  std::printf("\n%d x %d, %d step(s), %s: peak RSS %.1f MB, %.0f bytes a particle\n", n, n, steps, method.c_str(),
              1e-6 * 1024.0 * double(u.ru_maxrss), 1024.0 * double(u.ru_maxrss) * per);
  return 0;
}
