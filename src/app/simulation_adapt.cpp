// The mesh between steps: AMRC's adaptations, grid sequencing's stages and,
// on several ranks, the tiles moved after either. Between steps the
// minimiser never sees the mesh change under it (the paper checks every few
// CG iterations).
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "amrc/sequence.hpp"
#include "app/simulation.hpp"
#include "decomp/collective.hpp"
#include "decomp/rebalance.hpp"
#include "mesh/topology.hpp"

namespace drape {

// Grid sequencing: every mesh runs with the stage drag (the meshes only lead
// to the rest state, which drag does not change, and the finest one must
// settle too), and a coarse mesh's residual forces are measured in its own
// particles' weight (4^level finest ones), so that a step converges to the
// same relative accuracy on every mesh. Without it, the scene's physics.
// Its contact layer is the mesh's own (solver/setup.cpp).
void Simulation::stage_physics() {
  const int level = sequence_level_;
  model.drag = sequencing_ ? std::max(scene.solver.drag, scene.amrc.stage_drag) : scene.solver.drag;
  model.force_scale = finest_force_scale_ * std::ldexp(1.0, 2 * level);
  set_contact_layer(model.contact, scene, fabric, std::ldexp(cloth.grid.hi, level),
                    std::ldexp(cloth.grid.hj, level), std::fabs(model.gravity[2]), level > 0);
}

void Simulation::adapt() {
  AdaptStats a;
  {
    ScopedPhase ph(tm_, kAmrc);
    loop->refresh_ghosts(true);  // new particles take values from old corners, ghosts among them
    // With self-contact, leaves near another part of the cloth split (amrc/near.cpp).
    const Thresholds th{scene.amrc.refine, scene.amrc.coarsen, scene.amrc.coarsen_speed,
                        scene.amrc.indicator == AmrcIndicator::Deflection,
                        model.self_contact ? 2 * model.contact.thickness : 0.0};
    a = amrc->adapt(cloth, fabric.density, scene.cloth.shear, th, {&tiling, &dec_.owned, &red()},
                    &model.contact.obstacle);
  }
  sum_.refined += a.refined;
  sum_.coarsened += a.coarsened;
  sum_.refined_inside += a.refined_inside;
  sum_.refined_near += a.refined_near;
  if (a.refined != 0 || a.coarsened != 0) mesh_changed(false);
}

// Grid sequencing: the cloth at rest on a coarse mesh goes on on the next finer one.
void Simulation::next_stage() {
  {
    ScopedPhase ph(tm_, kAmrc);
    loop->refresh_ghosts(true);
    amrc->set_uniform_level(cloth, fabric.density, scene.cloth.shear, --sequence_level_);
  }
  // The finer mesh's elements reach half as far: so do the ghosts a rank
  // holds and the ring of elements it computes (the values came over first).
  if (ranks_ > 1) {
    ScopedPhase ph(tm_, kMigrate);
    set_ghost_widths(dec_, cloth, tiling, mesh_ghost_widths());
  }
  stage_physics();
  mesh_changed(true);
  const double eased = red().max(ease_stretched_edges(cloth, loop->evaluator()));
  ease_until_ = cloth.time + eased / kEaseRate;
  sum_.stages.push_back(
      {cloth.step, cloth.time, sequence_level_, sum_.active_final, stage_preconditioner_name()});
  sum_.counters.calm = 0;  // at rest on the coarser mesh, not on this one
  sum_.at_rest = false;
  if (talk_)
    std::printf("at rest after step %d (t = %.4g s): every leaf split, level %d now, %lld particles; "
                "edges eased from up to %.1f %% strain\n",
                cloth.step, cloth.time, sequence_level_, (long long)sum_.active_final, 100 * eased);
}

// When the wall budget left would not cover the next finer mesh
// (next_stage_seconds), the run ends here, at rest on this mesh, rather
// than out of time on the next one mid-motion.
bool Simulation::finer_mesh_fits() {
  const auto now = clock::now();
  const double stage = std::chrono::duration<double>(now - stage_start_).count();
  const StageTime last{stage, loop->preconditioner() == Preconditioner::Multigrid};
  const bool multigrid_next =
      scene.solver.method == SolverMethod::Newton &&
      stage_preconditioner(scene.solver, uniform_level_particles(cloth.grid, sequence_level_ - 1)) ==
          Preconditioner::Multigrid;
  const double next = next_stage_seconds(last, stage_before_, multigrid_next);
  const double left = scene.solver.wall_limit - std::chrono::duration<double>(now - t0_).count();
  const bool fits = root_decides(comm_, scene.solver.wall_limit <= 0 || next < left);
  if (fits) {
    stage_start_ = now;
    stage_before_ = last;
  } else if (talk_) {
    std::printf("at rest after step %d (t = %.4g s) on level %d: the next finer mesh would take "
                "about %.0f s of the %.0f s left (solver.wall_limit): ending here\n",
                cloth.step, cloth.time, sequence_level_, next, left);
  }
  sum_.sequence_cut_short = !fits;
  return fits;
}

void Simulation::mesh_changed(bool new_stage) {
  amrc->lift_new_particles(cloth, model.contact);
  if (ranks_ > 1) rebalance();
  rebuild_lists();
  loop->mesh_changed(new_stage);
  const int64_t active = active_particles(cloth);
  sum_.active_min = std::min(sum_.active_min, active);
  sum_.active_max = std::max(sum_.active_max, active);
  sum_.active_final = active;
  loop->set_solver(mesh_solver());  // `auto`: the multigrid from a mesh size on
}

void Simulation::rebalance() {
  ScopedPhase ph(tm_, kMigrate);
  Rebalance rb;
  rb.step = cloth.step;
  if (!drape::rebalance(dec_, cloth, tiling, scene.parallel.imbalance, comm_, rb)) return;
  // The cells' corners and the masses of the particles newly held
  // (Cloth::cell, Cloth::mass) from the tree.
  amrc->apply(cloth, fabric.density, scene.cloth.shear);
  own_blocks();
  sum_.rebalances.push_back(rb);
  if (talk_)
    std::printf("rebalance after step %d (%s): imbalance %.3f -> %.3f, %d tile(s) moved (%.1f kB), "
                "edge cut %lld\n",
                rb.step, rb.method, rb.imbalance_before, rb.imbalance_after, rb.tiles_moved,
                rb.bytes_moved / 1024.0, (long long)rb.edge_cut);
}

}  // namespace drape
