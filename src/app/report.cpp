// report.json and the closing tables (see report.hpp).
#include "app/report.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "app/signals.hpp"
#include "io/json.hpp"
#include "solver/contact.hpp"
#include "solver/drape_coefficient.hpp"

namespace drape {

Table2 table2(const LoopClock& a, const LoopClock& b, double time, int threads) {
  Table2 t;
  const double wall = b.wall - a.wall, busy = b.busy - a.busy;
  t.time = time;
  t.sequential = std::max(0.0, time - wall);
  t.parallel = std::max(0.0, wall - busy / threads);
  t.speedup = time > 0 ? (busy + t.sequential) / time : 1.0;
  return t;
}




const char* preconditioner_name(const SolverSpec& s) {
  return s.method == SolverMethod::Newton ? to_string(s.preconditioner) : "none";
}

double level_spacing(const Grid& g, int level) { return std::ldexp(std::max(g.hi, g.hj), level); }

std::string what_was_solved(const Scene& scene, const Cloth& cloth, const Summary& s, int64_t particles_solved) {
  const std::string pre = preconditioner_name(scene.solver);
  char b[512];
  std::snprintf(b, sizeof b,
                "%s, %d x %d grid: %s%lld particles solved, spacing %.3g mm; %s with %s; drag %g/s; "
                "t = %.4g s, %s",
                scene.name.c_str(), cloth.grid.ni, cloth.grid.nj,
                s.final_level > 0 ? ("on the level-" + std::to_string(s.final_level) + " mesh, ").c_str() : "",
                (long long)particles_solved, 1e3 * s.final_spacing, to_string(scene.solver.method),
                pre == "none" ? "no preconditioner" : (pre + " preconditioner").c_str(), s.drag, cloth.time,
                s.at_rest ? "at rest" : "still moving");
  std::string text = b;
  if (s.counters.unconverged > 0) text += ", " + std::to_string(s.counters.unconverged) + " unconverged step(s)";
  return text;
}

int64_t active_particles(const Cloth& c) {
  int64_t n = 0;
  for (uint8_t f : c.flags) n += f & kActive;
  return n;
}

double max_penetration(const Cloth& c, const Model& m, const ActiveLists& lists, const Reducer& red) {
  double worst = 0;
  for (int64_t p : lists.particles.items)
    worst = std::max(worst, penetration(m.contact.obstacle, c.x() + 3 * p));
  return red.max(worst);
}

double max_penetration_written(const Cloth& c, const Model& m, const Tiling& tiling, const std::vector<int>& owned,
                               const Reducer& red) {
  double worst = 0;
  for (int t : owned) {
    const TileRange r = tiling.range(t);
    for (int i = r.i0; i < r.i1; ++i)
      for (int j = r.j0; j < r.j1; ++j)
        if (!(c.flags[c.grid.id(i, j)] & kRemoved))  // no surface is written there
          worst = std::max(worst, penetration(m.contact.obstacle, c.x() + 3 * c.grid.id(i, j)));
  }
  return red.max(worst);
}

int64_t process_cpu_microseconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  auto us = [](const timeval& t) { return int64_t(t.tv_sec) * 1000000 + t.tv_usec; };
  return us(u.ru_utime) + us(u.ru_stime);
}

int64_t peak_rss_bytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return int64_t(u.ru_maxrss) * 1024;  // Linux counts it in KiB
}

std::string report_json(const Scene& scene, const Fabric& fabric, const Cloth& cloth,
                        const Summary& s, const Timers& tm, double wall, double cpu, int ranks, int threads,
                        const std::string& checksum, double penetration_depth, int64_t free_particles) {
  Json j;
  j.begin_object();
  j.value("program", std::string("drape ") + DRAPE_VERSION);
  j.value("scene", scene.name);
  j.begin_object("fabric").value("name", fabric.name).value("source", fabric.source)
      .value("density_kg_m2", fabric.density).end_object();
  j.value("particles", (long long)cloth.grid.n());  // the finest grid's
  // What was solved: the method, its preconditioner, the drag, and the final
  // mesh (its unknown particles over all ranks, its spacing).
  j.value("method", to_string(scene.solver.method));
  j.value("preconditioner", preconditioner_name(scene.solver));
  j.value("prediction", scene.solver.method == SolverMethod::Newton ? to_string(scene.solver.prediction) : "fall");
  j.value("drag", s.drag);
  j.value("stage_drag", s.sequencing ? scene.amrc.stage_drag : 0.0);
  j.begin_object("self_contact")
      .value("on", scene.solver.self_contact)
      .value("pair_builds", (long long)s.pair_builds)
      .value("pairs_listed", (long long)s.pairs_listed)
      .value("contact_ghosts", (long long)s.contact_ghosts)
      .value("pair_distance", s.pair_distance)
      .value("min_distance", s.closest_pair)  // null: no pairs listed
      .end_object();
  j.value("particles_solved", (long long)free_particles);
  j.value("final_spacing", s.final_spacing);
  j.begin_object("particles_active")
      .value("min", (long long)s.active_min)
      .value("max", (long long)s.active_max)
      .value("final", (long long)s.active_final)
      .value("mean", s.counters.iterations > 0 ? double(s.counters.particle_iterations) / s.counters.iterations
                                                : double(s.active_final))
      .end_object();
  j.begin_object("amrc")
      .value("enabled", scene.amrc.enabled)
      .value("refined", (long long)s.refined)
      .value("coarsened", (long long)s.coarsened)
      .value("refined_inside", (long long)s.refined_inside)
      .value("refined_near", (long long)s.refined_near)
      .value("start_spacing", scene.amrc.start_spacing)
      .end_object();
  // Grid sequencing: each uniform mesh, from the step it took over at.
  j.begin_array("stages");
  for (const Summary::Stage& g : s.stages)
    j.begin_object()
        .value("from_step", g.step)
        .value("from_time", g.time)
        .value("level", g.level)
        .value("particles", (long long)g.particles)
        .value("stage_preconditioner", g.preconditioner)
        // Names of their own: the top level's "steps" etc. stay the first match.
        .value("stage_steps", (long long)g.steps)
        .value("stage_newton_iterations", (long long)g.newton)
        .value("stage_linear_iterations", (long long)g.linear)
        .value("stage_evaluations", (long long)g.evaluations)
        .value("stage_retries", (long long)g.retries)
        .value("stage_contact_halvings", (long long)g.contact_halvings)
        .value("stage_multigrid_builds", (long long)g.multigrid_builds)
        .value("stage_rest_guesses", (long long)g.rest_guesses)
        .value("stage_seconds", g.seconds)
        .value("stage_cpu_seconds", g.cpu_seconds)
        .end_object();
  j.end_array();
  j.value("final_level", s.final_level);
  j.value("sequence_cut_short", s.sequence_cut_short);
  j.begin_array("grid").value(nullptr, cloth.grid.ni).value(nullptr, cloth.grid.nj).end_array();
  j.value("free_particles", (long long)free_particles);
  const RunCounters& n = s.counters;
  j.value("steps", cloth.step);
  j.value("steps_requested", scene.solver.steps);
  j.value("restarted_from_step", s.first_step);
  j.value("iterations", (long long)n.iterations);
  j.value("evaluations", (long long)n.evaluations);
  // Newton: its steps, and the linear CG's iterations (the `iterations` above).
  const bool newton = scene.solver.method == SolverMethod::Newton;
  j.value("newton_iterations", (long long)n.newton_iterations);
  j.value("linear_iterations", (long long)(newton ? n.iterations : 0));
  // The multigrid's levels (finest first): their size, V-cycles and seconds.
  j.begin_array("multigrid");
  for (const MultigridLevelStats& l : s.multigrid)
    j.begin_object()
        .value("particles", (long long)l.points)
        .value("blocks", (long long)l.blocks)
        .value("stride", l.stride)
        .value("cycles", (long long)l.cycles)
        .value("seconds", l.seconds)
        .value("setup_seconds", l.setup_seconds)
        .end_object();
  j.end_array();
  // Several ranks: what each rank receives to run the replicated V-cycle.
  const Summary::Gathered& mg = s.multigrid_gathered;
  j.begin_object("multigrid_gathered")
      .value("builds", (long long)mg.build_count)
      .value("per_build_bytes", (long long)mg.build)
      .value("per_cycle_bytes", (long long)mg.cycle)
      .value("builds_bytes", (long long)mg.builds)
      .value("cycles_bytes", (long long)mg.cycles)
      .value("cycles_cpu_seconds_largest_rank", mg.cpu_max)
      .value("cycles_cpu_seconds_all_ranks", mg.cpu_sum)
      .value("builds_cpu_seconds_largest_rank", mg.build_cpu_max)
      .value("builds_cpu_seconds_all_ranks", mg.build_cpu_sum)
      .end_object();
  j.value("simulated_seconds", cloth.time);
  j.value("iterations_per_simulated_second", cloth.time > 0 ? n.iterations / cloth.time : 0.0);
  j.value("max_iterations_in_a_step", (long long)n.max_step_iterations);
  j.value("unconverged_steps", (long long)n.unconverged);
  j.begin_object("dt").value("min", n.dt_min).value("max", n.dt_max).value("last", cloth.dt_prev).end_object();
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
  j.value("stopped_by_signal", s.signal ? signal_name(s.signal) : "");
  j.value("checkpoint", s.checkpoint);
  j.value("rest_speed", scene.solver.rest_speed);
  j.value("max_penetration", penetration_depth);  // over the solved particles
  j.value("max_penetration_written", s.penetration_written);  // over the written surface
  j.value("picture_positions", (long long)s.picture_positions);  // rank 0's, for drape.png
  j.value("projections", (long long)n.projections);
  j.begin_object("zigzag")
      .value("share", s.zigzag.share())
      .value("pairs", (long long)s.zigzag.pairs)
      .value("zigzags", (long long)s.zigzag.zigzags)
      .value("min_turn", kZigzagTurn)
      .end_object();
  if (is_drape_test(scene)) {  // from every rank's cells (Simulation::write_final_state)
    const DrapeTest& t = s.drape;
    j.value("drape_coefficient", t.coefficient);
    j.value("drape_nodes", t.nodes);
    j.begin_object("drape_areas").value("shadow", t.shadow).value("specimen", t.specimen).value("disc", t.disc).end_object();
  }
  j.value("total_mass", s.total_mass);
  j.value("wall_seconds", wall);
  j.value("cpu_seconds", cpu);
  j.value("peak_rss_bytes", (long long)s.peak_rss);
  j.value("estimated_peak_bytes_per_rank", (long long)s.estimated_rss);
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
  const DecompStats& d = s.decomp;
  j.begin_object("decomposition")
      .value("tiles", d.tiles)
      .value("tile", d.tile)
      .value("imbalance", d.imbalance)
      .value("edge_cut", (long long)d.edge_cut)
      .value("ghosts", (long long)d.ghosts)
      .value("ghost_width", d.ghost_width)
      .value("ring_width", d.ring_width)
      .value("halo_exchanges", (long long)d.exchanges)
      .value("halo_bytes", (long long)d.halo_bytes)
      .value("halo_seconds", d.halo_seconds)
      .value("reduction_seconds", d.reduction_seconds)
      .end_object();
  j.begin_array("rebalances");
  for (const Rebalance& r : s.rebalances)
    j.begin_object()
        .value("after_step", r.step)
        .value("imbalance_before", r.imbalance_before)
        .value("imbalance_after", r.imbalance_after)
        .value("tiles_moved", r.tiles_moved)
        .value("bytes_moved", (long long)r.bytes_moved)
        .value("edge_cut", (long long)r.edge_cut)
        .value("method", r.method)
        .end_object();
  j.end_array();
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

void print_timing_table(const Timers& tm, double wall, double cpu, const std::string& checksum, const DecompStats& d,
                        int ranks, int64_t peak_rss, const Summary::Gathered& gathered) {
  std::printf("\n%-16s %12s %8s\n", "phase", "seconds", "share");
  for (int p = 0; p < kPhases; ++p)
    std::printf("%-16s %12.3f %7.1f%%\n", phase_name(p), tm.seconds[p],
                wall > 0 ? 100.0 * tm.seconds[p] / wall : 0.0);
  if (ranks > 1) {  // inside the phases above; the largest over ranks
    std::printf("%-16s %12.3f %7.1f%%   (within the phases)\n", "  halo exchange", d.halo_seconds,
                wall > 0 ? 100.0 * d.halo_seconds / wall : 0.0);
    std::printf("%-16s %12.3f %7.1f%%   (within the phases)\n", "  reductions", d.reduction_seconds,
                wall > 0 ? 100.0 * d.reduction_seconds / wall : 0.0);
  }
  std::printf("%-16s %12.3f\n", "wall", wall);
  std::printf("%-16s %12.3f   (all ranks and threads)\n", "cpu", cpu);
  std::printf("%-16s %12.1f   MB (the largest rank's)\n", "peak RSS", 1e-6 * double(peak_rss));
  if (gathered.build > 0)  // the replicated V-cycle's inputs, received by each rank
    std::printf("%-16s %12.1f   MB a build (K's rows), %.2f MB a V-cycle; %.1f MB received in all\n", "multigrid gather",
                1e-6 * double(gathered.build), 1e-6 * double(gathered.cycle),
                1e-6 * double(gathered.builds + gathered.cycles));
  std::printf("state checksum   %s\n", checksum.c_str());
  std::fflush(stdout);
}

}  // namespace drape
