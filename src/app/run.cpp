// The main job on every rank: set up, step (Algorithm 1), write frames, the
// picture and the JSON report; progress and the timing table on rank 0.
#include "app/run.hpp"

#include <omp.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include "amrc/active_lists.hpp"
#include "decomp/collective.hpp"
#include "app/progress.hpp"
#include "io/error.hpp"
#include "io/json.hpp"
#include "io/output.hpp"
#include "solver/checksum.hpp"
#include "solver/time_loop.hpp"

namespace drape {

namespace {

namespace fs = std::filesystem;

void make_output_dir(const std::string& dir, MPI_Comm comm, int rank) {
  bool ok = true;
  std::string why;
  if (rank == 0) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir)) {
      ok = false;
      why = ec ? ec.message() : "not a directory";
    }
  }
  if (!root_decides(comm, ok))
    throw InputError("--output " + dir + ": cannot create the output directory (" + why + ")");
}

FrameView frame_of(const Cloth& c, const std::vector<Block>& owned) {
  FrameView f;
  f.ni = c.grid.ni;
  f.nj = c.grid.nj;
  f.step = c.step;
  f.time = c.time;
  f.x = c.x();
  f.tension = c.tension();
  f.moment = c.moment();
  f.shear = c.shear();
  f.flags = c.flags.data();
  f.level = c.level.data();
  f.owned = owned;
  return f;
}

void write_text_atomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    out << text << "\n";
    if (!out) throw std::runtime_error("cannot write " + tmp);
  }
  fs::rename(tmp, path);
}

// The paper's Table 2 columns for this run's time stepping: the time outside
// the parallel loops (sequential overhead), the time inside them beyond the
// busy thread time divided by the threads (parallel overhead: imbalance and
// synchronisation), and the speed-up this implies over one thread running
// the same busy work plus the sequential part.
struct Table2 {
  double time = 0, sequential = 0, parallel = 0, speedup = 1;
};

Table2 table2(const LoopClock& a, const LoopClock& b, double time, int threads) {
  Table2 t;
  const double wall = b.wall - a.wall, busy = b.busy - a.busy;
  t.time = time;
  t.sequential = std::max(0.0, time - wall);
  t.parallel = std::max(0.0, wall - busy / threads);
  t.speedup = time > 0 ? (busy + t.sequential) / time : 1.0;
  return t;
}

struct Summary {
  int steps = 0;
  long long iterations = 0, evaluations = 0, projections = 0;
  int max_step_iterations = 0, unconverged = 0;
  double dt_min = 1e300, dt_max = 0;
  bool at_rest = false;
  bool stopped_by_wall_limit = false;
  Table2 table2;
  StepStats last;
};

double max_penetration(const Cloth& c, const Model& m, const ActiveLists& lists, const Reducer& red) {
  double worst = 0;
  for (int64_t p : lists.particles.items)
    worst = std::max(worst, penetration(m.contact.obstacle, c.x() + 3 * p));
  return red.max(worst);
}

std::string report_json(const Scene& scene, const Fabric& fabric, const Cloth& cloth,
                        const Summary& s, const Timers& tm, double wall, int ranks, int threads,
                        const std::string& checksum, double penetration_depth, int64_t free_particles) {
  Json j;
  j.begin_object();
  j.value("program", std::string("drape ") + DRAPE_VERSION);
  j.value("scene", scene.name);
  j.begin_object("fabric").value("name", fabric.name).value("source", fabric.source)
      .value("density_kg_m2", fabric.density).end_object();
  j.value("particles", (long long)cloth.grid.n());
  j.begin_array("grid").value(nullptr, cloth.grid.ni).value(nullptr, cloth.grid.nj).end_array();
  j.value("free_particles", (long long)free_particles);
  j.value("steps", s.steps);
  j.value("steps_requested", scene.solver.steps);
  j.value("iterations", s.iterations);
  j.value("evaluations", s.evaluations);
  j.value("simulated_seconds", cloth.time);
  j.value("iterations_per_simulated_second", cloth.time > 0 ? s.iterations / cloth.time : 0.0);
  j.value("max_iterations_in_a_step", s.max_step_iterations);
  j.value("unconverged_steps", s.unconverged);
  j.begin_object("dt").value("min", s.dt_min).value("max", s.dt_max).value("last", s.last.dt).end_object();
  j.begin_object("final_cost")
      .value("total", s.last.cost.total())
      .value("newton", s.last.cost.newton)
      .value("stretch", s.last.cost.stretch)
      .value("bend", s.last.cost.bend)
      .value("shear", s.last.cost.shear)
      .value("per_particle", s.last.cost_per_particle)
      .end_object();
  j.value("max_speed", s.last.max_speed);
  j.value("at_rest", s.at_rest);
  j.value("stopped_by_wall_limit", s.stopped_by_wall_limit);
  j.value("rest_speed", scene.solver.rest_speed);
  j.value("max_penetration", penetration_depth);
  j.value("projections", s.projections);
  j.value("total_mass", cloth.total_mass());
  j.value("wall_seconds", wall);
  j.begin_object("phases");
  for (int p = 0; p < kPhases; ++p) j.value(phase_name(p), tm.seconds[p]);
  j.end_object();
  j.begin_object("table2")
      .value("time", s.table2.time)
      .value("sequential_overhead", s.table2.sequential)
      .value("parallel_overhead", s.table2.parallel)
      .value("speedup", s.table2.speedup)
      .end_object();
  j.value("ranks", ranks);
  j.value("threads", threads);
  j.value("schedule", to_string(scene.parallel.schedule));
  j.value("gradient", to_string(scene.solver.gradient));
  j.value("state_checksum", checksum);
  j.end_object();
  return j.str();
}

void print_table2(const Table2& t, int threads) {
  std::printf("\nTable 2 (time stepping, %d thread(s)): time %.3f s, sequential overhead %.3f s, "
              "parallel overhead %.3f s, speed-up %.2f\n",
              threads, t.time, t.sequential, t.parallel, t.speedup);
}

void print_timing_table(const Timers& tm, double wall, const std::string& checksum) {
  std::printf("\n%-16s %12s %8s\n", "phase", "seconds", "share");
  for (int p = 0; p < kPhases; ++p)
    std::printf("%-16s %12.3f %7.1f%%\n", phase_name(p), tm.seconds[p],
                wall > 0 ? 100.0 * tm.seconds[p] / wall : 0.0);
  std::printf("%-16s %12.3f\n", "wall", wall);
  std::printf("state checksum   %s\n", checksum.c_str());
  std::fflush(stdout);
}

}  // namespace

int run_simulation(const Scene& scene, const Fabric& fabric, const RunOptions& opt, MPI_Comm comm) {
  const auto t0 = std::chrono::steady_clock::now();
  const int rank = rank_of(comm), ranks = size_of(comm);
  if (scene.parallel.threads > 0) omp_set_num_threads(scene.parallel.threads);
  const int threads = omp_get_max_threads();
  const bool talk = rank == 0 && !opt.quiet;
  make_output_dir(opt.output_dir, comm, rank);
  if (talk && ranks > 1)
    std::printf("note: tile decomposition across ranks is not built yet; %d ranks replicate the "
                "work and write one file together\n", ranks);

  Timers tm;
  Cloth cloth;
  Model model;
  Tiling tiling;
  ActiveLists lists;
  std::vector<int> owned;
  {
    ScopedPhase ph(tm, kSetup);
    cloth = make_cloth(scene, fabric);
    model = make_model(scene, fabric, cloth.grid.hi, cloth.grid.hj);
    tiling = Tiling(cloth.grid.ni, cloth.grid.nj, scene.cloth.tile);
    for (int t = 0; t < tiling.count(); ++t) owned.push_back(t);
  }
  {
    ScopedPhase ph(tm, kLists);
    build_active_lists(cloth, tiling, owned, lists);
  }
  // Every rank holds every tile until the decomposition lands (issue 5), so
  // sums must not add ranks together: each rank reduces on its own, and all
  // get the same bits.
  LocalReducer red;
  LoopPolicy policy{scene.parallel.schedule, scene.parallel.chunk};
  TimeLoop loop(cloth, model, lists, tiling, policy, red, scene.solver);
  // Replicated work: rank 0 writes every block, the others join with none.
  std::vector<Block> blocks;
  if (rank == 0) blocks.push_back({0, cloth.grid.ni, 0, cloth.grid.nj});

  std::unique_ptr<Hdf5Output> h5;
  {
    ScopedPhase ph(tm, kOutput);
    h5 = std::make_unique<Hdf5Output>(opt.output_dir, comm, scene, opt.scene_toml, fabric,
                                      cloth.grid.ni, cloth.grid.nj);
    h5->write_frame(frame_of(cloth, blocks));
  }
  if (talk)
    std::printf("drape %s: %s, %d x %d particles (%lld free), fabric %s, %d rank(s) x %d thread(s)\n",
                DRAPE_VERSION, scene.name.c_str(), cloth.grid.ni, cloth.grid.nj,
                (long long)loop.free_particles(), fabric.name.c_str(), ranks, threads);

  Progress progress(talk, scene.solver.steps, scene.solver.wall_limit);
  Summary sum;
  // The budget is checked every iteration, on rank 0's clock, so that every
  // rank stops at the same iteration.
  auto over_budget = [&] {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return root_decides(comm, scene.solver.wall_limit > 0 && elapsed > scene.solver.wall_limit);
  };
  loop.stop_requested = over_budget;
  int calm = 0, last_frame = 0;  // frame 0 is written above
  const LoopClock clock0 = loop_clock();
  const auto stepping0 = std::chrono::steady_clock::now();
  for (int s = 0; s < scene.solver.steps; ++s) {
    const StepStats st = loop.step(tm, [&](int it, double cost) { progress.iteration(cloth.step + 1, it, cost); });
    sum.steps = st.step;
    sum.iterations += st.iterations;
    sum.evaluations += st.evaluations;
    sum.projections += st.projections;
    sum.max_step_iterations = std::max(sum.max_step_iterations, st.iterations);
    sum.unconverged += st.converged ? 0 : 1;
    sum.dt_min = std::min(sum.dt_min, st.dt);
    sum.dt_max = std::max(sum.dt_max, st.dt);
    sum.last = st;
    progress.step(st);
    const bool last = s + 1 == scene.solver.steps;
    calm = (scene.solver.rest_speed > 0 && st.max_speed < scene.solver.rest_speed) ? calm + 1 : 0;
    sum.at_rest = calm >= 3;
    if (!last && !sum.at_rest && scene.output.every > 0 && st.step % scene.output.every == 0) {
      ScopedPhase ph(tm, kOutput);
      h5->write_frame(frame_of(cloth, blocks));
      last_frame = st.step;
    }
    if (sum.at_rest) break;
    if ((st.stopped || over_budget()) && !last) {
      sum.stopped_by_wall_limit = true;
      if (talk) std::printf("wall limit of %.0f s reached after step %d: ending the run\n",
                            scene.solver.wall_limit, st.step);
      break;
    }
  }
  if (scene.solver.rest_speed <= 0) sum.at_rest = sum.last.max_speed < 1e-3;
  sum.table2 = table2(clock0, loop_clock(),
                      std::chrono::duration<double>(std::chrono::steady_clock::now() - stepping0).count(),
                      threads);
  const double depth = max_penetration(cloth, model, lists, red);
  const Checksum ck = state_checksum(cloth, tiling, owned, red);
  {
    ScopedPhase ph(tm, kOutput);
    if (cloth.step != last_frame) h5->write_frame(frame_of(cloth, blocks));  // the final state
    h5->finish();
    if (rank == 0 && scene.output.picture)
      render_picture(frame_of(cloth, blocks), scene.obstacle, opt.output_dir + "/drape.png");
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (rank == 0) {
    write_text_atomically(opt.output_dir + "/report.json",
                          report_json(scene, fabric, cloth, sum, tm, wall, ranks, threads, ck.hex(),
                                      depth, loop.free_particles()));
    if (!opt.quiet) {
      progress.finish(sum.at_rest, depth);
      print_timing_table(tm, wall, ck.hex());
      print_table2(sum.table2, threads);
    }
  }
  return 0;
}

}  // namespace drape
