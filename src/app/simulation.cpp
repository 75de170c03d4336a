// Setting a simulation up: the one-rank pieces for tests and tools, and the
// program's run on every rank (checks, restart, the first mesh, tiles over
// ranks, active lists, the time loop).
#include "app/simulation.hpp"

#include <omp.h>

#include <algorithm>
#include <stdexcept>

#include "amrc/remesh.hpp"
#include "amrc/sequence.hpp"
#include "app/memory.hpp"
#include "base/error.hpp"
#include "decomp/collective.hpp"
#include "mesh/topology.hpp"

namespace drape {

Simulation::Simulation(const Scene& s, const Fabric& f) : scene(s), fabric(f) {
  cloth = make_cloth(scene, fabric);
  model = make_model(scene, fabric, cloth.grid.hi, cloth.grid.hj);
  rebuild();
  progress_.emplace(false, scene.solver.steps);
}

Simulation::Simulation(const Scene& s, const Fabric& f, const RunOptions& opt, MPI_Comm comm)
    : scene(s), fabric(f), comm_(comm), rank_(rank_of(comm)), ranks_(size_of(comm)), opt_(opt) {
  refuse_unsupported();
  // Before any allocation the grid sizes and before the output directory.
  check_memory(scene, comm_);
  if (scene.parallel.threads > 0) omp_set_num_threads(scene.parallel.threads);
  threads_ = omp_get_max_threads();
  talk_ = rank_ == 0 && !opt_.quiet;
  {
    ScopedPhase ph(tm_, kSetup);
    if (ranks_ > 1) {
      set_up_in_slots();
    } else {
      tiling = Tiling(scene.cloth.particles[0], scene.cloth.particles[1], scene.cloth.tile);
      set_up_mesh(nullptr);
      dec_ = decompose(cloth, tiling, comm_, mesh_ghost_widths());  // refuses more ranks than tiles
      hold_own_particles(cloth, tiling, dec_);
    }
    if (opt_.restart) check_restart_digest();  // before anything is written
    set_up_model();
  }
  if (opt_.set_up_only) return;
  make_output_dir();
  rebuild_lists();
  sum_.active_min = sum_.active_max = sum_.active_final = active_particles(cloth);
  policy = LoopPolicy{scene.parallel.schedule, scene.parallel.chunk};
  loop = std::make_unique<TimeLoop>(cloth, model, lists, tiling, policy, red(), scene.solver, dec_.ghosts());
  loop->set_solver(mesh_solver());
  if (sequence_level_ > 0)
    sum_.stages.push_back(
        {cloth.step, cloth.time, sequence_level_, sum_.active_final, stage_preconditioner_name()});
  if (opt_.restart) loop->minimizer().set_first_step(opt_.restart->counters.cg_first_step);
  if (opt_.restart) restore_easing(opt_.restart->ease_until);
  own_blocks();
}

Simulation::~Simulation() = default;

void Simulation::refuse_unsupported() const {
  const SolverSpec& sv = scene.solver;
  const bool numeric = sv.gradient == GradientMode::Numeric;
  if (scene.amrc.enabled && numeric)
    throw InputError("amrc.enabled = true needs solver.gradient = \"analytic\" (the difference windows "
                     "do not follow hanging particles)");
  if (ranks_ > 1 && numeric)
    throw InputError("solver.gradient = \"numeric\" runs on one rank only (its difference windows "
                     "reach beyond the ghost particles); run it without mpirun");
  if (sv.self_contact && numeric)
    throw InputError("solver.self_contact = true (the default) needs solver.gradient = \"analytic\" (the "
                     "difference windows do not reach a particle's contact partners); set "
                     "solver.self_contact = false for the numeric gradient");
}

SolverSpec Simulation::mesh_solver() const {
  return stage_solver(scene.solver, sum_.active_final);
}

const char* Simulation::stage_preconditioner_name() const {
  return scene.solver.method == SolverMethod::Newton ? to_string(loop->preconditioner()) : "none";
}

// AMRC's leaves may be as coarse as its tree allows anywhere; grid
// sequencing's mesh is uniform, its elements as long as its level's.
GhostWidths Simulation::mesh_ghost_widths() const {
  if (!amrc) return ghost_widths(false, 0);
  return ghost_widths(true, scene.amrc.enabled ? amrc->tree().max_level() : sequence_level_);
}

// A run on several ranks, new or restarted: no rank makes or reads the
// whole cloth. Each makes its even share of the tiles, on the first mesh
// (a restart: the checkpoint's), to count their work for the partition,
// then only its own tiles' and ghosts' particles: the same values as the
// whole cloth's, held in slots from the start.
void Simulation::set_up_in_slots() {
  tiling = Tiling(scene.cloth.particles[0], scene.cloth.particles[1], scene.cloth.tile);
  dec_ = decompose_in_slots(cloth, tiling, comm_, [this](const std::vector<int64_t>& held) {
    amrc.reset();
    cloth = Cloth();  // before the next is made: the set-up's peak is one share's cloth
    set_up_mesh(&held);
    return mesh_ghost_widths();
  });
}

// The cloth, new or the checkpoint's, on its first mesh; `held`: a new
// cloth's particles made in slots (make_cloth), null: every particle.
void Simulation::set_up_mesh(const std::vector<int64_t>* held) {
  cloth = make_cloth(scene, fabric, held);
  const CheckpointState* ck = opt_.restart;
  if (ck) {
    read_restart_particles(*ck);
    rebuild_topology(cloth, scene.cloth.shear);
    rebuild_geometry(cloth, fabric.density);
    sum_.counters = ck->counters;
    sum_.first_step = cloth.step;
    last_checkpoint_ = cloth.step;
  }
  // The uniform level amrc.start_spacing asks a new run to start on (0: the finest).
  // A disc specimen is cut from the finest grid only: no coarse stages.
  const int start_level =
      scene.cloth.shape == ClothShape::Disc ? 0 : sequence_start_level(cloth.grid, scene.amrc.start_spacing);
  // A restart goes on on its checkpoint's mesh: the finest one where it holds no tree.
  if (!scene.amrc.enabled && !(ck && ck->amrc_levels.empty())) sequence_level_ = start_level;
  if (scene.amrc.enabled || sequence_level_ > 0) set_up_tree(start_level);  // from the finest mesh (paper), or the checkpoint's
}

// The checkpoint's values of the particles this rank holds, and the digest's
// sums of its tiles. A damaged file may fail on some ranks only (their
// rows): all ranks learn the first failure and refuse together.
void Simulation::read_restart_particles(const CheckpointState& ck) {
  std::string error;
  try {
    read_checkpoint_particles(ck, cloth, restart_eased_);
  } catch (const InputError& e) {
    error = e.what();
  }
  error = first_error(comm_, error);
  if (!error.empty()) throw InputError(error);
  restart_tile_sums_ = checkpoint_tile_sums(cloth, tiling, restart_eased_);
}

// Every rank sums its own tiles' particles: together, every particle once.
void Simulation::check_restart_digest() {
  uint64_t mine = 0;
  for (int t : dec_.owned) mine += restart_tile_sums_[size_t(t)];
  check_checkpoint_digest(*opt_.restart, sum_over_ranks(comm_, mine));
  restart_tile_sums_ = {};
}

void Simulation::set_up_tree(int start_level) {
  const CheckpointState* ck = opt_.restart;
  // The near-sheet search's room only where AMRC adapts (grid sequencing never does).
  amrc = std::make_unique<Amrc>(cloth, scene.amrc.enabled ? scene.amrc.max_level : sequence_level_,
                                scene.amrc.enabled && scene.solver.self_contact);
  if (ck && !ck->amrc_levels.empty()) {
    // Read on every rank alike, so every rank refuses a damaged tree here
    // (before the digest, which needs the mesh it makes).
    try {
      amrc->restore(ck->amrc_levels);
    } catch (const std::invalid_argument& e) {
      throw InputError("checkpoint " + ck->path + ": its AMRC tree is damaged (" + e.what() + ")");
    }
    if (sequence_level_ > 0) sequence_level_ = amrc->tree().levels().empty() ? 0 : amrc->tree().levels()[0];
  } else if (sequence_level_ > 0) {
    amrc->set_uniform_level(cloth, fabric.density, scene.cloth.shear, sequence_level_);
  } else if (scene.amrc.enabled && !ck && start_level > 0) {
    // AMRC starts on leaves that wide (at most max_level), not on the finest mesh: the
    // criterion coarsens a flat cloth one level per adaptation, and with coarsen_speed
    // the cloth is moving before it gets far, so the fall's mesh would depend on the grid.
    amrc->set_uniform_level(cloth, fabric.density, scene.cloth.shear, std::min(scene.amrc.max_level, start_level));
  }
  amrc->apply(cloth, fabric.density, scene.cloth.shear);
}

void Simulation::set_up_model() {
  model = make_model(scene, fabric, cloth.grid.hi, cloth.grid.hj);
  finest_force_scale_ = model.force_scale;
  sequencing_ = amrc && !scene.amrc.enabled;
  stage_physics();
}

void Simulation::rebuild() {
  if (amrc) {
    amrc->apply(cloth, fabric.density, scene.cloth.shear);
  } else {
    rebuild_topology(cloth, scene.cloth.shear);
    rebuild_geometry(cloth, fabric.density);
  }
  tiling = Tiling(cloth.grid.ni, cloth.grid.nj, scene.cloth.tile);
  dec_.owned.clear();
  for (int t = 0; t < tiling.count(); ++t) dec_.owned.push_back(t);
  rebuild_lists();
  policy = LoopPolicy{scene.parallel.schedule, scene.parallel.chunk};
  loop = std::make_unique<TimeLoop>(cloth, model, lists, tiling, policy, red(), scene.solver);
  sum_.active_final = active_particles(cloth);
  loop->set_solver(mesh_solver());
}

void Simulation::set_tree(const Quadtree& t) {
  amrc = std::make_unique<Amrc>(cloth, t.max_level(), scene.solver.self_contact);
  amrc->restore(t.levels());
}

const Reducer& Simulation::red() const {
  if (dec_.reducer) return *dec_.reducer;
  return local_red_;
}

void Simulation::rebuild_lists() {
  ScopedPhase ph(tm_, kLists);
  static const std::vector<int64_t> no_ring;
  build_active_lists(cloth, tiling, dec_.owned, lists, dec_.halo ? dec_.halo->ring() : no_ring);
  if (amrc) hanging_links(amrc->tree(), lists.hanging);
}

// A checkpoint inside grid sequencing's easing window goes on with the
// rest lengths eased so far, as the uninterrupted run does.
void Simulation::restore_easing(double until) {
  if (restart_eased_.empty()) return;
  ease_until_ = until;
  restore_eased_edges(cloth, loop->evaluator(), restart_eased_.data());
  restart_eased_ = {};
}

// Each rank writes its own tiles' blocks of every collective file.
void Simulation::own_blocks() {
  blocks_.clear();
  for (int t : dec_.owned) {
    const TileRange r = tiling.range(t);
    blocks_.push_back({r.i0, r.i1, r.j0, r.j1});
  }
}

}  // namespace drape
