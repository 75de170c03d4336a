// drape: the program's start. Parses flags, loads and validates the scene and
// fabric, then runs the Simulation. Exit status: 0 success, 2 bad
// input, 3 numerical failure, 1 internal error. Only rank 0 prints, except
// that an internal error is named by the rank it struck.
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>

#include "app/simulation.hpp"
#include "app/signals.hpp"
#include "decomp/collective.hpp"
#include "io/checkpoint.hpp"
#include "io/config.hpp"
#include "base/error.hpp"
#include "io/kes.hpp"

namespace {

// Every rank reaches the same verdict on input (all read the same files), so
// each can exit on its own without a hang; only rank 0 speaks.
int fail(int code, const std::string& what) {
  if (drape::rank_of(MPI_COMM_WORLD) == 0) std::cerr << "drape: error: " << what << "\n";
  MPI_Finalize();
  return code;
}

// An internal error may strike one rank alone while the others wait for it
// in a collective: that rank names itself and ends them all.
int fail_internal(const std::string& what) {
  if (drape::size_of(MPI_COMM_WORLD) == 1) return fail(1, "internal: " + what);
  drape::end_all_ranks(MPI_COMM_WORLD, what);
}

// --dry-run of a restart: every rank reads its particles of the checkpoint
// and the digest is checked over them, as the run would; nothing is written.
void check_restart(const drape::Scene& scene, const drape::Fabric& fabric, const drape::CheckpointState& ck) {
  drape::RunOptions opt;
  opt.quiet = true;
  opt.restart = &ck;
  opt.set_up_only = true;
  const drape::Simulation sim(scene, fabric, opt, MPI_COMM_WORLD);
}

}  // namespace

int main(int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  const bool root = drape::rank_of(MPI_COMM_WORLD) == 0;
  drape::install_stop_signals();
  drape::ignore_file_size_signal();

  CLI::App app{"drape: hybrid MPI+OpenMP simulation of woven cloth draping, with a "
               "material model built from Kawabata (KES) fabric measurements.\n"
               "Without --config it runs the embedded default: the paper's box drape."};
  std::string config_path, output_dir = "out", restart;
  std::vector<std::string> overrides;
  bool dry_run = false, quiet = false, help_config = false;
  int threads = 0;
  app.add_option("-c,--config", config_path, "scene file (TOML)");
  app.add_option("-s,--set", overrides, "override a scene key: section.key=value (repeatable)")
      ->allow_extra_args(false);
  app.add_option("-o,--output", output_dir,
                 "output directory (default: out; with --restart, the checkpoint's directory)");
  app.add_option("-r,--restart", restart,
                 "continue the run saved in a checkpoint (DIR/checkpoint.h5); --set may change "
                 "solver.steps, solver.wall_limit, output.* and parallel.*");
  app.add_option("-t,--threads", threads, "OpenMP threads per rank (default: OMP_NUM_THREADS)")
      ->check(CLI::Range(1, 1024));
  app.add_flag("--dry-run", dry_run, "validate, print the resolved scene and exit");
  app.add_flag("-q,--quiet", quiet, "no progress lines");
  app.add_flag("--help-config", help_config, "print the reference of every scene key (markdown) and exit");
  app.set_version_flag("-V,--version", std::string("drape ") + DRAPE_VERSION);

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    if (root) app.exit(e);
    MPI_Finalize();
    return 0;
  } catch (const CLI::ParseError& e) {
    return fail(2, e.what() + std::string(" (see drape --help)"));
  }
  if (help_config) {
    if (root) std::cout << drape::scene_reference();
    MPI_Finalize();
    return 0;
  }

  try {
    drape::Scene scene;
    drape::Fabric fabric;
    std::optional<drape::CheckpointState> resume;
    if (!restart.empty()) {
      // The scene and fabric come from the checkpoint, so that the run goes
      // on with exactly the physics it started with.
      if (!config_path.empty())
        throw drape::InputError("--restart " + restart + ": --config cannot be combined with "
                                "--restart (the checkpoint holds the scene)");
      drape::check_restart_overrides(overrides);
      resume = drape::read_checkpoint(restart);
      scene = drape::load_scene_text(resume->scene_toml, restart + " (scene_toml)", overrides);
      fabric = resume->fabric;
      // The thread count is this launch's, not the checkpoint's (the results
      // are the same on any): a run restarted on more ranks would otherwise
      // run its first launch's threads in each.
      if (!drape::overrides_key(overrides, "parallel.threads")) scene.parallel.threads = 0;
    } else {
      std::optional<std::string> cfg;
      if (!config_path.empty()) cfg = config_path;
      scene = drape::load_scene(cfg, overrides);
      fabric = drape::load_fabric(scene.cloth.fabric);
    }
    drape::check_particle_mass(scene, fabric.density, fabric.name);
    if (threads > 0) scene.parallel.threads = threads;
    const std::string toml = drape::scene_to_toml(scene);
    if (dry_run) {
      if (resume) check_restart(scene, fabric, *resume);
      if (root && resume)
        std::cout << "# restart from " << restart << " at step " << resume->step << "\n";
      if (root) std::cout << toml;
      MPI_Finalize();
      return 0;
    }
    drape::RunOptions opt;
    opt.output_dir = output_dir;
    // A restart goes on writing where the run was, unless told otherwise.
    if (resume && app.count("--output") == 0) {
      const std::filesystem::path dir = std::filesystem::path(restart).parent_path();
      opt.output_dir = dir.empty() ? "." : dir.string();
    }
    opt.scene_toml = toml;
    opt.quiet = quiet;
    if (resume) opt.restart = &*resume;
    int status = 0;
    {  // its communicators and files closed before MPI_Finalize
      drape::Simulation sim(scene, fabric, opt, MPI_COMM_WORLD);
      status = sim.run();
    }
    MPI_Finalize();
    return status;
  } catch (const drape::InputError& e) {
    return fail(2, e.what());
  } catch (const drape::NumericalError& e) {
    return fail(3, e.what());
  } catch (const drape::CollectiveError& e) {
    return fail(1, e.what());
  } catch (const std::exception& e) {
    return fail_internal(e.what());
  }
}
