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
// the scalars, scene and fabric (a sum over particles: any split of them
// adds up to it); a restart recomputes it, each rank over its own tiles, so
// a damaged or truncated file is refused rather than restarted from.
//
// Writing is collective: each rank writes the blocks it owns into
// checkpoint.h5.tmp, which is flushed to disk and then renamed over the
// previous checkpoint, so a complete checkpoint is always on disk. Reading
// is each rank's own: the metadata, then its held particles' rows.
#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

#include "io/frame.hpp"
#include "mesh/cloth.hpp"
#include "mesh/tiles.hpp"
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
// and each edge slot's rest length as eased so far (2 per held particle, at
// Cloth::pair_slot, 0 where none is listed; empty when none eases). A
// restart inside the window must continue from these, not from the
// material's lengths.
struct EasedEdges {
  double until = 0;
  std::vector<double> rest;
};

// What a checkpoint holds besides its particles: enough to make the cloth
// of its scene, which read_checkpoint_particles then fills.
struct CheckpointState {
  std::string path;
  std::string scene_toml;
  Fabric fabric;
  RunCounters counters;
  std::vector<uint8_t> amrc_levels;  // empty without AMRC
  Grid grid;                         // ni, nj
  int step = 0;
  double time = 0, dt = 0, dt_prev = 0;
  bool eased = false;                // the run was inside grid sequencing's easing window
  double ease_until = 0;
  std::string digest;
};

// Collective over `comm`. `owned`: the blocks this rank writes (eased.rest,
// when not empty, holds at least the owned particles' slots).
void write_checkpoint(const std::string& dir, MPI_Comm comm, const Cloth& cloth,
                      const std::vector<Block>& owned, const std::string& scene_toml,
                      const Fabric& fabric, const RunCounters& counters,
                      const std::vector<uint8_t>& amrc_levels = {}, const EasedEdges& eased = {});

// Reads a checkpoint's metadata on this rank alone and checks that its
// particle datasets are there. Throws InputError naming the file and what
// is wrong with it.
CheckpointState read_checkpoint(const std::string& path);

// Reads the particles `cloth` holds (all, or its slots on several ranks:
// hyperslabs of those rows only) into it, made for the checkpoint's scene,
// with the step, time and time steps; `eased` gets their eased edges
// (cleared where the checkpoint has none). Throws InputError; the file's
// digest is checked by check_checkpoint_digest.
void read_checkpoint_particles(const CheckpointState& ck, Cloth& cloth, std::vector<double>& eased);

// The digest's sum over the particles of each tile of `tiling` as `cloth`
// holds them (those of tiles it holds in part are partial: sum owned tiles only).
std::vector<uint64_t> checkpoint_tile_sums(const Cloth& cloth, const Tiling& tiling, const std::vector<double>& eased);

// Throws InputError where `particle_sum`, the tile sums of all tiles
// (summed over ranks), and the metadata do not give the file's digest.
void check_checkpoint_digest(const CheckpointState& ck, uint64_t particle_sum);

}  // namespace drape
