#pragma once
// The drape run: set up the cloth for a scene, step it (paper Algorithm 1),
// write output and the JSON report. Called by main() on every rank.
#include <mpi.h>

#include <string>

#include "solver/fabric.hpp"
#include "solver/scene.hpp"

namespace drape {

struct RunOptions {
  std::string output_dir = "out";
  std::string scene_toml;  // the resolved scene, stored in the outputs
  bool quiet = false;      // no progress lines
};

// Returns the process exit status (0 ok, 3 numerical failure).
int run_simulation(const Scene& scene, const Fabric& fabric, const RunOptions& opt, MPI_Comm comm);

}  // namespace drape
