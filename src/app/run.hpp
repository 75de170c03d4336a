#pragma once
// The drape run: set up the cloth for a scene, step it (paper Algorithm 1),
// write output and the JSON report. Called by main() on every rank.
#include <mpi.h>

#include <string>

#include "io/checkpoint.hpp"
#include "solver/fabric.hpp"
#include "solver/scene.hpp"

namespace drape {

struct RunOptions {
  std::string output_dir = "out";
  std::string scene_toml;  // the resolved scene, stored in the outputs
  bool quiet = false;      // no progress lines
  const CheckpointState* restart = nullptr;  // continue from this checkpoint
};

// Returns the process exit status (0 ok, also when a signal or the wall limit
// ended it with a checkpoint). Throws InputError and NumericalError.
int run_simulation(const Scene& scene, const Fabric& fabric, const RunOptions& opt, MPI_Comm comm);

}  // namespace drape
