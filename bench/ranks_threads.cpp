// Ranks x threads on the machine at hand (docs/performance.md, across ranks): under
// mpirun, each rank takes its METIS share of a 1000 x 1000 cloth mid-drape
// and runs a fixed number of the paper's CG iterations, and of Newton's
// inner CG iterations (stiffness products), with halo exchanges and tile-
// ordered reductions. Rank 0 prints one JSON line: time, the halo and
// reduction seconds (largest over ranks), imbalance and the checksum of the
// result, which must not depend on ranks or threads.
//   mpirun -np R ranks_threads [--size 1000] [--iterations 20]
#include <mpi.h>
#include <omp.h>

#include <CLI/CLI.hpp>
#include <sstream>

#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "decomp/decomposition.hpp"
#include "io/json.hpp"
#include "mid_drape.hpp"
#include "solver/checksum.hpp"

namespace drape {
namespace {

struct Result {
  double seconds = 0, halo = 0, reductions = 0;
  std::string checksum;
};

// One solver's run on this rank's share; `newton` picks the solver.
Result run(int n, int iterations, bool newton, MPI_Comm comm) {
  Simulation w(mid_drape_scene(n), load_fabric("denim-A"));  // every tile, to set the state up
  jitter_mid_drape(w, 7);
  Decomposition dec = decompose(w.cloth, w.tiling, comm);
  ActiveLists lists;
  build_active_lists(w.cloth, w.tiling, dec.owned, lists, dec.halo ? dec.halo->ring() : std::vector<int64_t>{});
  TimeLoop loop(w.cloth, w.model, lists, w.tiling, w.policy, *dec.reducer, w.scene.solver, dec.ghosts());
  loop.freeze_bend_axes();
  CgSettings cs;
  cs.max_iterations = iterations;
  cs.tolerance = 0;
  cs.free_particles = loop.free_particles();
  Timers tm;
  NewtonSolver nw(w.cloth, loop.minimizer());
  MPI_Barrier(comm);
  const double h0 = dec.halo_seconds(), r0 = dec.reduction_seconds();
  const auto t0 = std::chrono::steady_clock::now();
  if (newton) nw.minimize(loop.evaluator(), w.cloth.z.data(), cs, tm);
  else loop.minimizer().minimize(loop.evaluator(), w.cloth.z.data(), cs, tm);
  MPI_Barrier(comm);
  Result r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  double mine[2] = {dec.halo_seconds() - h0, dec.reduction_seconds() - r0}, most[2];
  MPI_Allreduce(mine, most, 2, MPI_DOUBLE, MPI_MAX, comm);
  r.halo = most[0];
  r.reductions = most[1];
  r.checksum = state_checksum(w.cloth, w.tiling, dec.owned, *dec.reducer).hex();
  return r;
}

}  // namespace
}  // namespace drape

int main(int argc, char** argv) {
  using namespace drape;
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int n = 1000, iterations = 20, rank = 0, ranks = 1;
  CLI::App app{"ranks_threads: CG and Newton iterations on this rank layout (under mpirun)"};
  app.option_defaults()->always_capture_default();
  app.add_option("--size", n, "particles per side")->check(CLI::Range(9, 100000));
  app.add_option("--iterations", iterations, "iterations of each solver")->check(CLI::Range(1, 1000000));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {  // every rank parses the same flags: all leave alike
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    std::ostringstream quiet;  // rank 0 alone says what was wrong
    const int code = (rank == 0 ? app.exit(e) : app.exit(e, quiet, quiet)) == 0 ? 0 : 2;
    MPI_Finalize();
    return code;
  }
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  const Result cg = run(n, iterations, false, MPI_COMM_WORLD);
  const Result newton = run(n, iterations, true, MPI_COMM_WORLD);
  if (rank == 0) {
    Json j;
    j.begin_object();
    j.value("particles", (long long)n * n);
    j.value("ranks", ranks);
    j.value("threads", omp_get_max_threads());
    j.value("iterations", iterations);
    for (auto [name, r] : {std::pair{"cg", cg}, std::pair{"newton", newton}})
      j.begin_object(name)
          .value("seconds", r.seconds)
          .value("halo_seconds", r.halo)
          .value("reduction_seconds", r.reductions)
          .value("checksum", r.checksum)
          .end_object();
    j.end_object();
    std::printf("%s\n", j.str().c_str());
  }
  MPI_Finalize();
  return 0;
}
