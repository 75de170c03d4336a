#pragma once
// Grid sequencing: the drape found on coarser meshes first. The run starts
// with every quadtree leaf at one coarse level; each time the cloth comes to
// rest, every leaf splits (Amrc::set_uniform_level), and the finer mesh starts
// from the coarser one's rest state, its tensions and moments included. The
// finest mesh's rest ends the run, or a coarser one's when the wall budget
// left (solver.wall_limit) would not cover the next finer mesh. A coarse mesh crosses the long,
// slow part of the drape (the fall, the swing of the sides) at a coarse
// mesh's price; each finer one only has to settle what it resolves anew.
#include "mesh/cloth.hpp"

namespace drape {

// The level of the first mesh: the coarsest whose spacing stays within
// `spacing` (m), and coarse enough to keep at least 8 intervals per side;
// 0 (start on the finest mesh) when spacing is 0 or below the grid's.
int sequence_start_level(const Grid& g, double spacing);

// The particles of the uniform mesh at `level` (a side's last interval
// clipped: the 1000 x 1000 grid's level 5 has 33 x 33).
int64_t uniform_level_particles(const Grid& g, int level);

// A finished stage's wall seconds (0: none yet) and whether the multigrid
// preconditioned its Newton steps (else Jacobi).
struct StageTime {
  double seconds = 0;
  bool multigrid = false;
};

// The wall time the next finer mesh will take, from the last two stages'
// and the preconditioner the next one takes: at least 8 times the last
// with Jacobi next (4 times the particles, twice the linear iterations a
// solve: halving the spacing doubles them), kMultigridStageGrowth times with the
// multigrid next (the default run's level 3 came to rest after 6.9 times
// level 4's CPU seconds on one thread, 8.2 times its wall seconds on two
// from level 4's checkpoint: 8.5 lets it start where it will finish), and the
// growth the last refinement showed when larger and one preconditioner
// solved all three. A stage that starts near rest can grow less than that
// (the default run's level 4 took 4.0 times level 5's time), and its
// successor then did not reach rest in the time left. Jacobi to the
// multigrid (solver.preconditioner = "auto") takes the multigrid's floor:
// the switch is meant where both cost alike on the last mesh.
constexpr double kJacobiStageGrowth = 8.0;
constexpr double kMultigridStageGrowth = 8.5;
double next_stage_seconds(StageTime last, StageTime before, bool multigrid_next);

}  // namespace drape

namespace drape {

class Evaluator;

// A split's new particle on a coarse edge that crossed an obstacle's rim
// is lifted out of the obstacle, and its two new edges come out stretched
// (a quarter longer at a box edge: the chord cut the corner, the cloth must
// go round it); released at once, they fling the cloth (12 m/s seen). So
// the split eases them: each edge stretched beyond 1 % gets a rest length
// that leaves it 1 %, which shrinks back to the material's at `rate` (strain per
// second). The rest lengths are the evaluator's (its listed edges', the
// ring's too), laid out from the mesh at each list change. Returns the
// largest strain eased on this rank's edges.
constexpr double kEaseRate = 2.0;  // strain per second
double ease_stretched_edges(const Cloth& c, Evaluator& ev);
// One step of dt: rest lengths move rate * dt (strain) back towards the material's.
void relax_eased_edges(const Cloth& c, Evaluator& ev, double rate, double dt);
// What a checkpoint keeps of the easing: this rank's own listed edges' rest
// lengths by slot (by_slot: 2 per particle c holds, at Cloth::pair_slot;
// other slots untouched).
void eased_rest_by_slot(const Cloth& c, Evaluator& ev, double* by_slot);
// A restart's: every listed edge (the ring's too) takes its slot's rest
// length from by_slot (a checkpoint's, for the particles c holds).
void restore_eased_edges(const Cloth& c, Evaluator& ev, const double* by_slot);

}  // namespace drape
