// The main job on every rank: set up, step (Algorithm 1), write frames, the
// picture and the JSON report; progress and the timing table on rank 0.
#include "app/run.hpp"

#include <omp.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <memory>
#include <stdexcept>

#include "mesh/active_lists.hpp"
#include "mesh/topology.hpp"
#include "amrc/amrc.hpp"
#include "amrc/remesh.hpp"
#include "amrc/sequence.hpp"
#include "decomp/collective.hpp"
#include "decomp/decomposition.hpp"
#include "decomp/gather.hpp"
#include "decomp/rebalance.hpp"
#include "app/memory.hpp"
#include "app/progress.hpp"
#include "app/report.hpp"
#include "app/signals.hpp"
#include "io/atomic_file.hpp"
#include "base/error.hpp"
#include "io/json.hpp"
#include "io/output.hpp"
#include "solver/checksum.hpp"
#include "solver/drape_coefficient.hpp"
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

// Test hook (fault injection): DRAPE_FAULT_NAN_STEP=k poisons one free
// particle's position before step k, so the numerical-failure path (exit 3,
// the last checkpoint kept) can be exercised on purpose.
int fault_step() {
  const char* v = std::getenv("DRAPE_FAULT_NAN_STEP");
  return v ? std::atoi(v) : 0;
}

// Test hook: DRAPE_FAULT_INTERNAL_RANK=r makes rank r alone throw an internal
// error before the step DRAPE_FAULT_NAN_STEP names, the way a bug on one
// rank would, so that the others are seen not to wait for it.
int fault_internal_rank() {
  const char* v = std::getenv("DRAPE_FAULT_INTERNAL_RANK");
  return v ? std::atoi(v) : -1;
}

void inject_nan(Cloth& c, const ActiveLists& lists) {
  for (int64_t p : lists.particles.items)
    if (c.free(p)) {
      c.x1[3 * p + 2] = std::numeric_limits<double>::quiet_NaN();  // the prediction carries it
      return;
    }
}

// A file rank 0 writes alone (the picture, the report): its failure (a full
// disk) is every rank's, so that all end with the same status and message.
template <class Write>
void on_root_agreed(MPI_Comm comm, Write&& write) {
  std::string error;
  if (rank_of(comm) == 0) try {
      write();
    } catch (const std::exception& e) {
      error = e.what();
    }
  error = root_error(comm, error);
  if (!error.empty()) throw CollectiveError(error);
}

void add_step(RunCounters& n, const StepStats& st, int64_t active) {
  n.iterations += st.iterations;
  n.particle_iterations += st.iterations * active;
  n.evaluations += st.evaluations;
  n.newton_iterations += st.newton_iterations;
  n.projections += st.projections;
  n.max_step_iterations = std::max<int64_t>(n.max_step_iterations, st.iterations);
  n.unconverged += st.converged ? 0 : 1;
  n.dt_min = std::min(n.dt_min, st.dt);
  n.dt_max = std::max(n.dt_max, st.dt);
}

// Grid sequencing: every mesh runs with the stage drag (the meshes only lead
// to the rest state, which drag does not change, and the finest one must
// settle too), and a coarse mesh's residual forces are measured in its own
// particles' weight (4^level finest ones), so that a step converges to the
// same relative accuracy on every mesh. Without it, the scene's physics.
// Its contact layer is the mesh's own (solver/setup.cpp).
void stage_physics(Model& m, const Scene& scene, const Fabric& fabric, const Grid& grid, double finest_force_scale,
                   bool sequencing, int level) {
  m.drag = sequencing ? std::max(scene.solver.drag, scene.amrc.stage_drag) : scene.solver.drag;
  m.force_scale = finest_force_scale * std::ldexp(1.0, 2 * level);
  set_contact_layer(m.contact, scene, fabric, std::ldexp(grid.hi, level), std::ldexp(grid.hj, level),
                    std::fabs(m.gravity[2]), level > 0);
}

}  // namespace

int run_simulation(const Scene& scene, const Fabric& fabric, const RunOptions& opt, MPI_Comm comm) {
  const auto t0 = std::chrono::steady_clock::now();
  const int rank = rank_of(comm), ranks = size_of(comm);
  if (scene.amrc.enabled && scene.solver.gradient == GradientMode::Numeric)
    throw InputError("amrc.enabled = true needs solver.gradient = \"analytic\" (the difference windows "
                     "do not follow hanging particles)");
  if (ranks > 1 && scene.solver.gradient == GradientMode::Numeric)
    throw InputError("solver.gradient = \"numeric\" runs on one rank only (its difference windows "
                     "reach beyond the ghost particles); run it without mpirun");
  if (scene.solver.self_contact && scene.amrc.enabled)
    throw InputError("solver.self_contact = true needs amrc.enabled = false (a coarse leaf's particles lie "
                     "further apart than the pair distance: the cloth would pass between them)");
  if (scene.solver.self_contact && scene.solver.gradient == GradientMode::Numeric)
    throw InputError("solver.self_contact = true needs solver.gradient = \"analytic\" (the difference "
                     "windows do not reach a particle's contact partners)");
  if (ranks > 1 && scene.solver.self_contact)
    throw InputError("solver.self_contact = true runs on one rank only (a partner may lie on another rank "
                     "beyond the ghost ring); run it without mpirun");
  if (ranks > 1 && scene.solver.preconditioner == Preconditioner::Multigrid)
    throw InputError("solver.preconditioner = \"multigrid\" runs on one rank only (its levels are not "
                     "split over ranks yet); run it without mpirun or use \"jacobi\"");
  // Before any allocation the grid sizes and before the output directory.
  check_memory(scene, comm);
  if (scene.parallel.threads > 0) omp_set_num_threads(scene.parallel.threads);
  const int threads = omp_get_max_threads();
  const bool talk = rank == 0 && !opt.quiet;

  Timers tm;
  Cloth cloth;
  Model model;
  Tiling tiling;
  ActiveLists lists;
  Decomposition dec;
  std::unique_ptr<Amrc> amrc;
  int sequence_level = 0;  // grid sequencing: the uniform mesh's level now (0: finest, or off)
  double finest_force_scale = 0;
  bool sequencing = false;  // the run started on a coarser mesh (or its checkpoint was on one)
  Summary sum;
  int last_frame = -1;  // the step of the last frame written (-1: none yet)
  {
    ScopedPhase ph(tm, kSetup);
    cloth = make_cloth(scene, fabric);
    if (opt.restart) {
      restore_state(*opt.restart, cloth);
      rebuild_topology(cloth, scene.cloth.shear);
      rebuild_geometry(cloth, fabric.density);
      sum.counters = opt.restart->counters;
      sum.first_step = cloth.step;
    }
    // The uniform level amrc.start_spacing asks a new run to start on (0: the finest).
    // A disc specimen is cut from the finest grid only: no coarse stages.
    const int start_level =
        scene.cloth.shape == ClothShape::Disc ? 0 : sequence_start_level(cloth.grid, scene.amrc.start_spacing);
    // A restart goes on on its checkpoint's mesh: the finest one where it holds no tree.
    if (!scene.amrc.enabled && !(opt.restart && opt.restart->amrc_levels.empty())) sequence_level = start_level;
    if (scene.amrc.enabled || sequence_level > 0) {  // from the finest mesh (paper), or the checkpoint's
      amrc = std::make_unique<Amrc>(cloth, scene.amrc.enabled ? scene.amrc.max_level : sequence_level);
      if (opt.restart && !opt.restart->amrc_levels.empty()) {
        amrc->restore(opt.restart->amrc_levels);
        if (sequence_level > 0) sequence_level = amrc->tree().levels().empty() ? 0 : amrc->tree().levels()[0];
      } else if (sequence_level > 0) {
        amrc->set_uniform_level(cloth, fabric.density, scene.cloth.shear, sequence_level);
      } else if (scene.amrc.enabled && !opt.restart && start_level > 0) {
        // AMRC starts on leaves that wide (at most max_level), not on the finest mesh: the
        // criterion coarsens a flat cloth one level per adaptation, and with coarsen_speed
        // the cloth is moving before it gets far, so the fall's mesh would depend on the grid.
        amrc->set_uniform_level(cloth, fabric.density, scene.cloth.shear, std::min(scene.amrc.max_level, start_level));
      }
      amrc->apply(cloth, fabric.density, scene.cloth.shear);
    }
    model = make_model(scene, fabric, cloth.grid.hi, cloth.grid.hj);
    finest_force_scale = model.force_scale;
    sequencing = amrc && !scene.amrc.enabled;
    stage_physics(model, scene, fabric, cloth.grid, finest_force_scale, sequencing, sequence_level);
    tiling = Tiling(cloth.grid.ni, cloth.grid.nj, scene.cloth.tile);
    // refuses more ranks than tiles
    dec = decompose(cloth, tiling, comm,
                    ghost_widths(amrc != nullptr, amrc ? amrc->tree().max_level() : 0));
  }
  make_output_dir(opt.output_dir, comm, rank);
  const std::vector<int64_t> no_ring;
  auto rebuild_lists = [&] {
    ScopedPhase ph(tm, kLists);
    build_active_lists(cloth, tiling, dec.owned, lists, dec.halo ? dec.halo->ring() : no_ring);
    if (amrc) hanging_links(amrc->tree(), lists.hanging);
  };
  rebuild_lists();
  sum.active_min = sum.active_max = sum.active_final = active_particles(cloth);
  if (sequence_level > 0) sum.stages.push_back({cloth.step, cloth.time, sequence_level, sum.active_final});
  const std::vector<int>& owned = dec.owned;
  const Reducer& red = *dec.reducer;
  LoopPolicy policy{scene.parallel.schedule, scene.parallel.chunk};
  TimeLoop loop(cloth, model, lists, tiling, policy, red, scene.solver, dec.ghosts());
  if (opt.restart) loop.minimizer().set_first_step(opt.restart->counters.cg_first_step);
  // Each rank writes its own tiles' blocks of every collective file.
  std::vector<Block> blocks;
  auto own_blocks = [&] {
    blocks.clear();
    for (int t : dec.owned) {
      const TileRange r = tiling.range(t);
      blocks.push_back({r.i0, r.i1, r.j0, r.j1});
    }
  };
  own_blocks();

  // From here on files are open collectively: an error that struck this
  // rank alone must end every rank before unwinding reaches a collective
  // close (the others would wait in it, or in the step's exchange, forever).
  // So the output lives outside the try, and is closed after the handler.
  std::unique_ptr<Hdf5Output> h5;
  try {
    // The state as written: ghosts and hanging particles current, inactive
    // particles on their leaf's surface.
    auto settle_for_output = [&] {
      loop.refresh_ghosts(false);
      if (amrc) amrc->fill_inactive(cloth);
    };
    auto write_frame = [&] {
      settle_for_output();
      h5->write_frame(frame_of(cloth, blocks));
    };
    {
      ScopedPhase ph(tm, kOutput);
      h5 = std::make_unique<Hdf5Output>(opt.output_dir, comm, scene, opt.scene_toml, fabric,
                                        cloth.grid.ni, cloth.grid.nj, opt.restart ? cloth.step : -1);
      // A restart drops the interrupted part's final frame unless it lies on
      // the frame cadence, so the continued file matches an uninterrupted run's.
      if (!opt.restart || (scene.output.every > 0 && cloth.step % scene.output.every == 0)) {
        write_frame();
        last_frame = cloth.step;
      }
    }
    if (talk) {
      // The grid, and the mesh solved first when that is a coarser one (grid sequencing).
      char mesh[128] = "";
      if (sequence_level > 0)
        std::snprintf(mesh, sizeof mesh, ", solved first on the level-%d mesh (spacing %.3g mm)", sequence_level,
                      1e3 * level_spacing(cloth.grid, sequence_level));
      std::printf("drape %s: %s, %d x %d grid (%lld particles free)%s, fabric %s, %d rank(s) x %d thread(s)\n",
                  DRAPE_VERSION, scene.name.c_str(), cloth.grid.ni, cloth.grid.nj,
                  (long long)loop.free_particles(), mesh, fabric.name.c_str(), ranks, threads);
      if (ranks > 1)
        std::printf("tiles: %d of %d x %d particles, METIS over %d ranks: imbalance %.3f, edge cut %lld, "
                    "rank 0 has %lld ghosts from %d neighbour(s)\n",
                    tiling.count(), scene.cloth.tile, scene.cloth.tile, ranks, dec.partition.imbalance,
                    (long long)dec.partition.edge_cut, (long long)dec.halo->ghosts(), dec.halo->neighbours());
      if (opt.restart)
        std::printf("continuing %s from step %d (t = %.6g s)\n", opt.restart->path.c_str(), cloth.step,
                    cloth.time);
    }

    Progress progress(talk, scene.solver.steps, scene.solver.wall_limit, cloth.step);
    // Stop requests are polled every iteration and agreed on by all ranks, so
    // that every rank stops at the same iteration: a signal on any rank, or
    // the wall-clock budget on rank 0's clock. Code: 2 * signal + budget.
    int stop_code = 0;
    auto stop_now = [&] {
      if (stop_code) return true;
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const bool budget = rank == 0 && scene.solver.wall_limit > 0 && elapsed > scene.solver.wall_limit;
      stop_code = max_over_ranks(comm, 2 * stop_signal() + (budget ? 1 : 0));
      return stop_code != 0;
    };
    loop.stop_requested = stop_now;
    auto checkpoint = [&] {
      ScopedPhase ph(tm, kOutput);
      sum.counters.cg_first_step = loop.minimizer().first_step();
      write_checkpoint(opt.output_dir, comm, cloth, blocks, opt.scene_toml, fabric, sum.counters,
                       amrc ? amrc->tree().levels() : std::vector<uint8_t>{});
      sum.checkpoint = opt.output_dir + "/checkpoint.h5";
      return cloth.step;
    };
    const int every = scene.output.every, ck_every = scene.output.checkpoint_every;
    const int poison = fault_step();
    const int poison_rank = fault_internal_rank();  // -1: the step is poisoned with a NaN
    int last_checkpoint = opt.restart ? cloth.step : -1;
    // AMRC between steps (the paper checks every few CG iterations; between
    // steps the minimiser never sees the mesh change under it).
    auto mesh_changed = [&](bool new_stage) {
      amrc->lift_new_particles(cloth, model.contact);
      if (ranks > 1) {
        ScopedPhase ph(tm, kMigrate);
        Rebalance rb;
        rb.step = cloth.step;
        if (rebalance(dec, cloth, tiling, scene.parallel.imbalance, comm, rb)) {
          own_blocks();
          sum.rebalances.push_back(rb);
          if (talk)
            std::printf("rebalance after step %d (%s): imbalance %.3f -> %.3f, %d tile(s) moved (%.1f kB), "
                        "edge cut %lld\n",
                        rb.step, rb.method, rb.imbalance_before, rb.imbalance_after, rb.tiles_moved,
                        rb.bytes_moved / 1024.0, (long long)rb.edge_cut);
        }
      }
      rebuild_lists();
      loop.mesh_changed(new_stage);
      const int64_t active = active_particles(cloth);
      sum.active_min = std::min(sum.active_min, active);
      sum.active_max = std::max(sum.active_max, active);
      sum.active_final = active;
    };
    auto adapt_mesh = [&] {
      AdaptStats a;
      {
        ScopedPhase ph(tm, kAmrc);
        loop.refresh_ghosts(true);  // new particles take values from old corners, ghosts among them
        const Thresholds th{scene.amrc.refine, scene.amrc.coarsen, scene.amrc.coarsen_speed,
                            scene.amrc.indicator == AmrcIndicator::Deflection};
        a = amrc->adapt(cloth, fabric.density, scene.cloth.shear, th, {&tiling, &dec.owned, &red},
                        &model.contact.obstacle);
      }
      sum.refined += a.refined;
      sum.coarsened += a.coarsened;
      sum.refined_inside += a.refined_inside;
      if (a.refined != 0 || a.coarsened != 0) mesh_changed(false);
    };
    // Grid sequencing: the cloth at rest on a coarse mesh goes on on the next finer one.
    double ease_until = 0;  // stretched edges eased by the last split relax until this time
    auto refine_everywhere = [&] {
      {
        ScopedPhase ph(tm, kAmrc);
        loop.refresh_ghosts(true);
        amrc->set_uniform_level(cloth, fabric.density, scene.cloth.shear, --sequence_level);
      }
      stage_physics(model, scene, fabric, cloth.grid, finest_force_scale, sequencing, sequence_level);
      mesh_changed(true);
      const double eased = red.max(ease_stretched_edges(cloth, lists.edges, lists.ring_edges));
      ease_until = cloth.time + eased / kEaseRate;
      sum.stages.push_back({cloth.step, cloth.time, sequence_level, sum.active_final});
      if (talk)
        std::printf("at rest after step %d (t = %.4g s): every leaf split, level %d now, %lld particles; "
                    "edges eased from up to %.1f %% strain\n",
                    cloth.step, cloth.time, sequence_level, (long long)sum.active_final, 100 * eased);
    };
    // When the wall budget left would not cover the next finer mesh
    // (next_stage_seconds), the run ends here, at rest on this mesh, rather
    // than out of time on the next one mid-motion.
    auto stage_start = std::chrono::steady_clock::now();
    double stage_before = 0;  // the previous stage's wall seconds
    auto finer_mesh_fits = [&] {
      const auto now = std::chrono::steady_clock::now();
      const double stage = std::chrono::duration<double>(now - stage_start).count();
      const double next = next_stage_seconds(stage, stage_before);
      const double left = scene.solver.wall_limit - std::chrono::duration<double>(now - t0).count();
      const bool fits = root_decides(comm, scene.solver.wall_limit <= 0 || next < left);
      if (fits) {
        stage_start = now;
        stage_before = stage;
      } else if (talk) {
        std::printf("at rest after step %d (t = %.4g s) on level %d: the next finer mesh would take "
                    "about %.0f s of the %.0f s left (solver.wall_limit): ending here\n",
                    cloth.step, cloth.time, sequence_level, next, left);
      }
      sum.sequence_cut_short = !fits;
      return fits;
    };
    const double g = std::sqrt(model.gravity[0] * model.gravity[0] + model.gravity[1] * model.gravity[1] +
                               model.gravity[2] * model.gravity[2]);
    const LoopClock clock0 = loop_clock();
    const auto stepping0 = std::chrono::steady_clock::now();
    while (cloth.step < scene.solver.steps) {
      if (poison == cloth.step + 1 && poison_rank < 0) inject_nan(cloth, lists);
      if (poison == cloth.step + 1 && poison_rank == rank)
        throw std::logic_error("fault injected on purpose (DRAPE_FAULT_INTERNAL_RANK)");
      const auto step_start = std::chrono::steady_clock::now();
      const int64_t step_cpu = process_cpu_microseconds();
      const StepStats st =
          loop.step(tm, [&](int it, double cost) { progress.iteration(cloth.step + 1, it, cost); });
      if (st.stopped) break;
      if (!sum.stages.empty())
        sum.stages.back().add(st, std::chrono::duration<double>(std::chrono::steady_clock::now() - step_start).count(),
                              1e-6 * double(process_cpu_microseconds() - step_cpu));
      add_step(sum.counters, st, sum.active_final);
      sum.last = st;
      const bool easing = cloth.time < ease_until;
      if (easing) relax_eased_edges(cloth, lists.edges, lists.ring_edges, kEaseRate, st.dt);
      progress.step(st, amrc ? sum.active_final : -1);
      const bool reached = scene.solver.end_time > 0 && cloth.time >= scene.solver.end_time;
      const bool last = st.step == scene.solver.steps || reached;
      sum.counters.calm = (scene.solver.rest_speed > 0 && st.max_speed < scene.solver.rest_speed && !easing)
                              ? sum.counters.calm + 1 : 0;
      // Three calm steps, spanning at least the time a cloth let go from rest
      // takes to pass rest_speed twice over: the top of a fall is not rest.
      const double calm_span = g > 0 ? 2 * scene.solver.rest_speed / (g * st.dt) : 0;
      sum.at_rest = sum.counters.calm >= std::max(3.0, std::ceil(calm_span));
      if (sum.at_rest && sequence_level > 0 && !last && finer_mesh_fits()) {
        refine_everywhere();
        sum.counters.calm = 0;
        sum.at_rest = false;
      }
      if (!last && !sum.at_rest && every > 0 && st.step % every == 0) {
        ScopedPhase ph(tm, kOutput);
        write_frame();
        last_frame = st.step;
      }
      if (scene.amrc.enabled && st.step % scene.amrc.every == 0) adapt_mesh();
      if (ck_every > 0 && st.step % ck_every == 0) last_checkpoint = checkpoint();
      if (sum.at_rest || reached || stop_now()) break;
    }
    sum.signal = stop_code / 2;
    sum.final_level = sequence_level;
    sum.sequencing = sequencing;
    sum.drag = model.drag;
    sum.pair_builds = loop.evaluator().self_contact().builds();
    sum.pairs_listed = loop.evaluator().self_contact().listed();
    // The final mesh's spacing: the uniform mesh's when sequencing, the finest
    // leaf's with AMRC (every rank holds the whole tree), else the grid's.
    int finest_leaf = sequence_level;
    if (scene.amrc.enabled && amrc && !amrc->tree().levels().empty())
      finest_leaf = *std::min_element(amrc->tree().levels().begin(), amrc->tree().levels().end());
    sum.final_spacing = level_spacing(cloth.grid, finest_leaf);
    sum.stopped_by_wall_limit = stop_code == 1;
    // A stopped run always leaves a checkpoint to continue from; a finished
    // one does when checkpoints were asked for.
    if ((stop_code || ck_every > 0) && last_checkpoint != cloth.step) last_checkpoint = checkpoint();
    if (talk && sum.stopped_by_wall_limit)
      std::printf("wall limit of %.0f s reached after step %d: ending the run\n", scene.solver.wall_limit,
                  cloth.step);
    if (rank == 0 && sum.signal)
      std::printf("%s received: the step in progress was rolled back; the state after step %d is in "
                  "%s (continue with: drape --restart %s)\n",
                  signal_name(sum.signal), cloth.step, sum.checkpoint.c_str(), sum.checkpoint.c_str());
    if (scene.solver.rest_speed <= 0) sum.at_rest = sum.last.max_speed < 1e-3;
    sum.table2 = table2(clock0, loop_clock(),
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - stepping0).count(),
                        threads);
    sum.decomp = decomp_stats(dec, tiling, comm);
    const double depth = max_penetration(cloth, model, lists, red);
    sum.zigzag = count_zigzags(cloth, lists.particles.items, red);
    sum.multigrid = loop.newton().multigrid_stats();
    loop.release_solvers();  // stepping is over: the picture reuses their memory
    settle_for_output();
    sum.penetration_written = max_penetration_written(cloth, model, tiling, owned, red);
    const Checksum ck = state_checksum(cloth, tiling, owned, red);
    {
      ScopedPhase ph(tm, kOutput);
      if (cloth.step != last_frame) write_frame();  // the final state
      h5->finish();
      if (scene.output.picture || is_drape_test(scene)) gather_on_root(cloth.x(), 3, tiling, dec.partition.owner, comm);
      if (scene.output.picture)
        on_root_agreed(comm, [&] {
          render_picture(frame_of(cloth, blocks), scene.obstacle, opt.output_dir + "/drape.png", 1024, 768,
                         what_was_solved(scene, cloth, sum, loop.free_particles()));
        });
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double cpu = 1e-6 * double(red.sum_i64(process_cpu_microseconds()));  // collective
    sum.peak_rss = int64_t(red.max(double(peak_rss_bytes())));                    // collective; exact below 2^53
    on_root_agreed(comm, [&] {
      write_file_atomically(opt.output_dir + "/report.json",
                            report_json(scene, fabric, cloth, sum, tm, wall, cpu, ranks, threads, ck.hex(),
                                        depth, loop.free_particles()) + "\n");
    });
    if (rank == 0) {
      if (!opt.quiet) {
        Progress::Solved solved;
        solved.method = to_string(scene.solver.method);
        solved.preconditioner = preconditioner_name(scene.solver);
        solved.level = sequence_level;
        solved.particles = loop.free_particles();
        solved.spacing = sum.final_spacing;
        solved.ni = cloth.grid.ni;
        solved.nj = cloth.grid.nj;
        solved.unconverged = sum.counters.unconverged;
        solved.written = sum.penetration_written;
        solved.projections = sum.counters.projections;
        progress.finish(sum.at_rest, depth, sum.zigzag.share(), solved);
        print_timing_table(tm, wall, cpu, ck.hex(), sum.decomp, ranks, sum.peak_rss);
        print_table2(sum.table2, threads);
      }
    }
    return 0;
  } catch (const InputError&) {
    throw;
  } catch (const NumericalError&) {
    throw;
  } catch (const CollectiveError&) {
    throw;
  } catch (const std::exception& e) {
    if (ranks == 1) throw;
    end_all_ranks(comm, e.what());
  }
}

}  // namespace drape
