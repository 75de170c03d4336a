#pragma once
// Checkpoints: DIR/checkpoint.h5 holds the whole state of a run between two
// time steps, in global particle order, so that `drape --restart` continues
// it bit for bit on any number of ranks and threads.
//
// Layout of checkpoint.h5
//   /            attributes: format = "drape checkpoint", format_version,
//                drape_version, ni, nj, step, time, dt, dt_prev, scene_toml,
//                counters (RunCounters), digest (see below)
//   /state/      positions, tension, moment, shear (the unknowns z), x1, x2
//                (the step history), flags, level: (NI x NJ [x C]) arrays;
//                eased_rest (NI x NJ x 2), only while grid sequencing's edges
//                ease: edge slot 2p + d's rest length (0 where none is
//                listed), with the root attribute ease_until (s)
//   /fabric/     attributes name, source; dataset numbers (KES values, SI);
//                one (n x 2) dataset per measured curve
//   /amrc_levels the AMRC tree: leaf level per finest interval, (NI-1 x NJ-1),
//                only when AMRC is on
//
// The digest hashes every particle's values with its global id together with
// the scalars, scene and fabric; reading recomputes it, so a damaged or
// truncated file is refused rather than restarted from.
//
// Writing is collective: each rank writes the blocks it owns into
// checkpoint.h5.tmp, which is flushed to disk and then renamed over the
// previous checkpoint, so a complete checkpoint is always on disk.
#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

#include "io/frame.hpp"
#include "mesh/cloth.hpp"
#include "solver/fabric.hpp"

namespace drape {

// What the driver carries from step to step besides the cloth.
struct RunCounters {
  int64_t iterations = 0, evaluations = 0, projections = 0;
  int64_t max_step_iterations = 0, unconverged = 0;
  int64_t calm = 0;               // consecutive steps below the rest speed
  int64_t particle_iterations = 0;  // CG iterations times the active particles, summed over steps
  double dt_min = 1e300, dt_max = 0;
  double cg_first_step = 1.0;     // nonlinear CG's carried first trial step
  int64_t newton_iterations = 0;  // Newton steps (solver.method = newton; iterations are then linear CG's)
};

// Grid sequencing's eased edges (amrc/sequence.hpp): until when they relax,
// and each edge slot's rest length as eased so far (2 per particle, grid
// order, 0 where none is listed; empty when none eases). A restart inside
// the window must continue from these, not from the material's lengths.
struct EasedEdges {
  double until = 0;
  std::vector<double> rest;
};

struct CheckpointState {
  std::string path;
  std::string scene_toml;
  Fabric fabric;
  RunCounters counters;
  std::vector<uint8_t> amrc_levels;  // empty without AMRC
  EasedEdges eased;
  // Grid, unknowns, history, flags, levels, step, time, dt, dt_prev; the
  // rest of the cloth is rebuilt from the scene and the flags.
  Cloth cloth;
};

// Collective over `comm`. `owned`: the blocks this rank writes (eased.rest,
// when not empty, is grid-sized with at least the owned blocks' slots set).
void write_checkpoint(const std::string& dir, MPI_Comm comm, const Cloth& cloth,
                      const std::vector<Block>& owned, const std::string& scene_toml,
                      const Fabric& fabric, const RunCounters& counters,
                      const std::vector<uint8_t>& amrc_levels = {}, const EasedEdges& eased = {});

// Reads and verifies a checkpoint on this rank alone. Throws InputError
// naming the file and what is wrong with it.
CheckpointState read_checkpoint(const std::string& path);

// Copies a checkpoint's state into a cloth made for the same scene.
void restore_state(const CheckpointState& ck, Cloth& cloth);

}  // namespace drape
