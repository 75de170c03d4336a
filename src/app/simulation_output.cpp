// What a run leaves: the output directory, HDF5/XDMF frames, checkpoints,
// the picture, report.json, and rank 0's banner and closing tables.
#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "app/memory.hpp"
#include "app/picture_samples.hpp"
#include "app/signals.hpp"
#include "app/simulation.hpp"
#include "base/error.hpp"
#include "decomp/collective.hpp"
#include "decomp/gather.hpp"
#include "io/atomic_file.hpp"
#include "io/picture.hpp"
#include "solver/checksum.hpp"
#include "solver/drape_coefficient.hpp"

namespace drape {

namespace {

namespace fs = std::filesystem;

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
  f.slot = c.slots();
  f.flags = c.flags.data();
  f.level = c.level.data();
  f.owned = owned;
  return f;
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

}  // namespace

void Simulation::make_output_dir() const {
  const std::string& dir = opt_.output_dir;
  bool ok = true;
  std::string why;
  if (rank_ == 0) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir)) {
      ok = false;
      why = ec ? ec.message() : "not a directory";
    }
  }
  if (!root_decides(comm_, ok))
    throw InputError("--output " + dir + ": cannot create the output directory (" + why + ")");
}

void Simulation::start() {
  open_output();
  print_banner();
  progress_.emplace(talk_, scene.solver.steps, scene.solver.wall_limit, cloth.step);
  loop->stop_requested = [this] { return stop_now(); };
  arm_faults();
  stage_start_ = clock::now();
  clock0_ = loop_clock();
  stepping0_ = clock::now();
}

void Simulation::open_output() {
  ScopedPhase ph(tm_, kOutput);
  h5_ = std::make_unique<Hdf5Output>(opt_.output_dir, comm_, scene, opt_.scene_toml, fabric, cloth.grid.ni,
                                     cloth.grid.nj, opt_.restart ? cloth.step : -1);
  // A restart drops the interrupted part's final frame unless it lies on
  // the frame cadence, so the continued file matches an uninterrupted run's.
  if (!opt_.restart || due(scene.output.every, cloth.step)) {
    write_frame();
    last_frame_ = cloth.step;
  }
}

void Simulation::print_banner() const {
  if (!talk_) return;
  // The grid, and the mesh solved first when that is a coarser one (grid sequencing).
  char mesh[128] = "";
  if (sequence_level_ > 0)
    std::snprintf(mesh, sizeof mesh, ", solved first on the level-%d mesh (spacing %.3g mm)", sequence_level_,
                  1e3 * level_spacing(cloth.grid, sequence_level_));
  std::printf("drape %s: %s, %d x %d grid (%lld particles free)%s, fabric %s, %d rank(s) x %d thread(s)\n",
              DRAPE_VERSION, scene.name.c_str(), cloth.grid.ni, cloth.grid.nj, (long long)loop->free_particles(),
              mesh, fabric.name.c_str(), ranks_, threads_);
  if (ranks_ > 1)
    std::printf("tiles: %d of %d x %d particles, METIS over %d ranks: imbalance %.3f, edge cut %lld, "
                "rank 0 has %lld ghosts from %d neighbour(s)\n",
                tiling.count(), scene.cloth.tile, scene.cloth.tile, ranks_, dec_.partition.imbalance,
                (long long)dec_.partition.edge_cut, (long long)dec_.halo->ghosts(), dec_.halo->neighbours());
  if (opt_.restart)
    std::printf("continuing %s from step %d (t = %.6g s)\n", opt_.restart->path.c_str(), cloth.step, cloth.time);
}

// The state as written: ghosts and hanging particles current, inactive
// particles on their leaf's surface.
void Simulation::settle_for_output() {
  loop->refresh_ghosts(false);
  if (amrc) amrc->fill_inactive(cloth);
}

void Simulation::write_frame() {
  settle_for_output();
  h5_->write_frame(frame_of(cloth, blocks_));
}

void Simulation::write() {
  ScopedPhase ph(tm_, kOutput);
  write_frame();
  last_frame_ = cloth.step;
}

void Simulation::checkpoint() {
  ScopedPhase ph(tm_, kOutput);
  sum_.counters.cg_first_step = loop->minimizer().first_step();
  write_checkpoint(opt_.output_dir, comm_, cloth, blocks_, opt_.scene_toml, fabric, sum_.counters,
                   amrc ? amrc->tree().levels() : std::vector<uint8_t>{}, easing());
  sum_.checkpoint = opt_.output_dir + "/checkpoint.h5";
  last_checkpoint_ = cloth.step;
}

// Inside grid sequencing's easing window, the edges' rest lengths as eased
// so far (this rank's own slots); outside it, nothing.
EasedEdges Simulation::easing() {
  EasedEdges e;
  if (!(cloth.time < ease_until_)) return e;
  e.until = ease_until_;
  e.rest.assign(size_t(2 * cloth.layout.m), 0.0);
  eased_rest_by_slot(cloth, loop->evaluator(), e.rest.data());
  return e;
}

void Simulation::finish() {
  summarise();
  double depth = 0;
  std::string checksum;
  write_final_state(depth, checksum);
  write_report(depth, checksum);
}

// How the run ended and on which mesh; a stopped run's checkpoint.
void Simulation::summarise() {
  sum_.signal = stop_code_ / 2;
  sum_.final_level = sequence_level_;
  sum_.total_mass = total_mass(cloth, tiling, dec_.owned, red());  // collective
  sum_.sequencing = sequencing_;
  sum_.drag = model.drag;
  sum_.pair_builds = loop->evaluator().self_contact().builds();
  sum_.pairs_listed = red().sum_i64(loop->evaluator().self_contact().listed());  // each rank lists its own
  sum_.contact_ghosts = red().sum_i64(loop->evaluator().self_contact().contact_ghosts());
  // How close the cloth came to itself: the final list's nearest pair at
  // the final positions (the last evaluation's, so the partners' are current).
  const SelfContact& sc = loop->evaluator().self_contact();
  sum_.pair_distance = sc.distance();
  sum_.closest_pair = -red().max(-sc.closest(loop->evaluator().lists().particles, cloth.z.data()));
  // The final mesh's spacing: the uniform mesh's when sequencing, the finest
  // leaf's with AMRC (every rank holds the whole tree), else the grid's.
  int finest_leaf = sequence_level_;
  if (scene.amrc.enabled && amrc && !amrc->tree().levels().empty())
    finest_leaf = *std::min_element(amrc->tree().levels().begin(), amrc->tree().levels().end());
  sum_.final_spacing = level_spacing(cloth.grid, finest_leaf);
  sum_.stopped_by_wall_limit = stop_code_ == 1;
  // A stopped run always leaves a checkpoint to continue from; a finished
  // one does when checkpoints were asked for.
  if ((stop_code_ || scene.output.checkpoint_every > 0) && last_checkpoint_ != cloth.step) checkpoint();
  if (talk_ && sum_.stopped_by_wall_limit)
    std::printf("wall limit of %.0f s reached after step %d: ending the run\n", scene.solver.wall_limit, cloth.step);
  if (rank_ == 0 && sum_.signal)
    std::printf("%s received: the step in progress was rolled back; the state after step %d is in "
                "%s (continue with: drape --restart %s)\n",
                signal_name(sum_.signal), cloth.step, sum_.checkpoint.c_str(), sum_.checkpoint.c_str());
  if (scene.solver.rest_speed <= 0) sum_.at_rest = sum_.last.max_speed < 1e-3;
  sum_.table2 = table2(clock0_, loop_clock(), std::chrono::duration<double>(clock::now() - stepping0_).count(),
                       threads_);
  sum_.decomp = decomp_stats(dec_, tiling, comm_);
}

// The final frame and picture; the penetration and checksum of the state.
void Simulation::write_final_state(double& depth, std::string& checksum) {
  const Reducer& r = red();
  depth = max_penetration(cloth, model, lists, r);
  sum_.zigzag = count_zigzags(cloth, lists.particles.items, r);
  const NewtonSolver& newton = loop->newton();
  sum_.multigrid = newton.multigrid_stats();
  sum_.multigrid_gathered = {newton.multigrid_build_bytes(), newton.multigrid_cycle_bytes(),
                             newton.multigrid_builds_bytes(), newton.multigrid_cycles_bytes(),
                             newton.multigrid_builds()};
  sum_.multigrid_gathered.cpu_max = r.max(newton.precondition_cpu_seconds());  // collective
  sum_.multigrid_gathered.cpu_sum = 1e-6 * double(r.sum_i64(int64_t(1e6 * newton.precondition_cpu_seconds())));
  sum_.multigrid_gathered.build_cpu_max = r.max(newton.build_cpu_seconds());
  sum_.multigrid_gathered.build_cpu_sum = 1e-6 * double(r.sum_i64(int64_t(1e6 * newton.build_cpu_seconds())));
  loop->release_solvers();  // stepping is over: the picture reuses their memory
  settle_for_output();
  sum_.penetration_written = max_penetration_written(cloth, model, tiling, dec_.owned, r);
  checksum = state_checksum(cloth, tiling, dec_.owned, r).hex();
  ScopedPhase ph(tm_, kOutput);
  if (cloth.step != last_frame_) write_frame();  // the final state
  h5_->finish();
  if (is_drape_test(scene)) drape_figures_on_root();
  if (scene.output.picture) draw_picture();
}

// Each rank covers its own tiles' cells; rank 0 counts the or of the covers.
void Simulation::drape_figures_on_root() {
  DrapeCover cover = drape_cover(cloth, cloth.x(), scene, tiling, dec_.owned);
  or_on_root(cover.shadow, comm_);
  or_on_root(cover.specimen, comm_);
  if (rank_ == 0) sum_.drape = drape_figures(cloth, scene, cover);
}

// Rank 0 draws from the positions the picture samples, sent by their
// owners; from the whole cloth only where one of those is not finite (a
// run that failed).
void Simulation::draw_picture() {
  const PicturePlan plan = plan_picture(cloth.grid.ni, cloth.grid.nj, cloth.flags.data());
  PictureSurface samples;
  size_t values = 0;
  const bool sampled = picture_samples_on_root(plan, cloth.x(), tiling, dec_.partition.owner, comm_, samples, &values);
  if (!sampled) gather_on_root(cloth.x(), 3, tiling, dec_.partition.owner, comm_);
  sum_.picture_positions = sampled ? int64_t(values / 3) : cloth.grid.n();
  on_root_agreed(comm_, [&] {
    const std::string path = opt_.output_dir + "/drape.png";
    const std::string what = what_was_solved(scene, cloth, sum_, loop->free_particles());
    if (sampled) render_picture(samples, scene.obstacle, path, 1024, 768, what);
    else render_picture(frame_of(cloth, blocks_), scene.obstacle, path, 1024, 768, what);
  });
}

void Simulation::write_report(double depth, const std::string& checksum) {
  const double wall = std::chrono::duration<double>(clock::now() - t0_).count();
  const double cpu = 1e-6 * double(red().sum_i64(process_cpu_microseconds()));  // collective
  sum_.peak_rss = int64_t(red().max(double(peak_rss_bytes())));                // collective; exact below 2^53
  sum_.estimated_rss = estimated_bytes_per_rank(scene, ranks_);
  on_root_agreed(comm_, [&] {
    write_file_atomically(opt_.output_dir + "/report.json",
                          report_json(scene, fabric, cloth, sum_, tm_, wall, cpu, ranks_, threads_, checksum, depth,
                                      loop->free_particles()) +
                              "\n");
  });
  if (rank_ != 0 || opt_.quiet) return;
  Progress::Solved solved;
  solved.method = to_string(scene.solver.method);
  solved.preconditioner = preconditioner_name(scene.solver);
  solved.level = sequence_level_;
  solved.particles = loop->free_particles();
  solved.spacing = sum_.final_spacing;
  solved.ni = cloth.grid.ni;
  solved.nj = cloth.grid.nj;
  solved.unconverged = sum_.counters.unconverged;
  solved.written = sum_.penetration_written;
  solved.projections = sum_.counters.projections;
  progress_->finish(sum_.at_rest, depth, sum_.zigzag.share(), solved);
  print_timing_table(tm_, wall, cpu, checksum, sum_.decomp, ranks_, sum_.peak_rss, sum_.multigrid_gathered);
  print_table2(sum_.table2, threads_);
}

}  // namespace drape
