#pragma once
// One simulation of a scene: the cloth, its model, tiles, active lists, time
// loop and AMRC tree, and, for the drape program, what a run adds on every
// rank: the decomposition, output files, checkpoints, the report. Its phases
// are members: set up (constructors), step, adapt, next
// stage (grid sequencing), rebalance, write, checkpoint, finish; run() drives
// them. Tests, benchmarks and tools use the one-rank constructor and the
// public parts directly.
#include <mpi.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "amrc/amrc.hpp"
#include "amrc/sequence.hpp"
#include "app/progress.hpp"
#include "app/report.hpp"
#include "decomp/decomposition.hpp"
#include "io/checkpoint.hpp"
#include "io/output.hpp"
#include "mesh/active_lists.hpp"
#include "mesh/quadtree.hpp"
#include "solver/fabric.hpp"
#include "solver/model.hpp"
#include "solver/reducer.hpp"
#include "solver/scene.hpp"
#include "solver/time_loop.hpp"
#include "solver/timers.hpp"

namespace drape {

struct RunOptions {
  std::string output_dir = "out";
  std::string scene_toml;  // the resolved scene, stored in the outputs
  bool quiet = false;      // no progress lines
  const CheckpointState* restart = nullptr;  // continue from this checkpoint
  // --dry-run of a restart: set up (each rank's particles read, the digest
  // checked over the ranks), then nothing made or written; run() not called.
  bool set_up_only = false;
};

// A step is calm (towards rest) below this speed: solver.rest_speed, or with
// friction on, kCreepSlips slips eps a step (the creep lagged friction lets
// a held particle make), whichever is larger.
constexpr double kCreepSlips = 3;
double calm_speed(const SolverSpec& sv, const Contact& c, double dt);

class Simulation {
 public:
  // One rank, every tile owned, no files, no checks: the pieces on the
  // scene's finest mesh (or a tree set_tree gives).
  Simulation(const Scene& scene, const Fabric& fabric);
  // The drape program on every rank of comm: refuses scenes it cannot run
  // (InputError), sets up a new run or continues opt.restart, creates the
  // output directory.
  Simulation(const Scene& scene, const Fabric& fabric, const RunOptions& opt, MPI_Comm comm);
  ~Simulation();
  // Neither copied nor moved: the time loop refers to the members (the
  // cloth, model, lists, tiling); a helper returns a std::unique_ptr.
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  // The whole run: the first frame, steps to the end, the final state and
  // the report. Returns the exit status (0 also when a signal or the wall
  // limit ended it with a checkpoint). Throws InputError, NumericalError,
  // CollectiveError; ends every rank on any other error of one rank.
  int run();

  // The run's phases, in the order run() reaches them (rebalance through
  // adapt and next_stage, when the mesh changed).
  void start();             // output files, the first frame, the banner
  StepStats step();         // one time step (stopped: rolled back, nothing counted)
  struct Ending {
    bool last = false;     // solver.steps or solver.end_time reached
    bool reached = false;  // solver.end_time reached
  };
  Ending ending(const StepStats& st);  // after a step: rest (in the summary), the end
  bool finer_mesh_fits();   // grid sequencing: the wall budget left covers the next mesh
  void next_stage();        // grid sequencing: every leaf split
  void adapt();             // AMRC: the tree follows the cloth
  void rebalance();         // several ranks: tiles move after the mesh changed
  void write();             // one frame
  void checkpoint();        // the state to continue from
  void finish();            // the final state, picture, report, tables

  // One rank: after changing flags (fixing particles), the tree or the
  // policy, the lists and the time loop built again.
  void rebuild();
  // One rank: the mesh as tree t (same grid) from the next rebuild() on.
  void set_tree(const Quadtree& t);
  // n >= 1 steps, each as step() takes it; the last one's record.
  StepStats advance(int n);
  // The AMRC tree; none: the finest grid.
  const Quadtree* tree() const { return amrc ? &amrc->tree() : nullptr; }
  const Reducer& red() const;
  const std::vector<int>& owned() const { return dec_.owned; }
  const Summary& summary() const { return sum_; }  // the counts report.json gives, so far

  Scene scene;
  Fabric fabric;
  Cloth cloth;
  Model model;
  Tiling tiling;
  ActiveLists lists;
  LoopPolicy policy;
  std::unique_ptr<TimeLoop> loop;
  std::unique_ptr<Amrc> amrc;  // AMRC or grid sequencing's mesh

 private:
  using clock = std::chrono::steady_clock;

  void refuse_unsupported() const;
  // The solver settings for the current mesh, `auto` resolved
  // (stage_solver), and the preconditioner's name a stage reports.
  SolverSpec mesh_solver() const;
  const char* stage_preconditioner_name() const;
  void set_up_mesh(const std::vector<int64_t>* held);
  void set_up_in_slots();
  GhostWidths mesh_ghost_widths() const;
  void set_up_tree(int start_level);
  void set_up_model();
  void stage_physics();
  void rebuild_lists();
  void mesh_changed(bool new_stage);
  void own_blocks();
  void restore_easing(double until);
  void read_restart_particles(const CheckpointState& ck);
  void check_restart_digest();
  EasedEdges easing();
  void make_output_dir() const;
  void open_output();
  void write_frame();
  void settle_for_output();
  void print_banner() const;
  void arm_faults();
  void inject_faults();
  void account(const StepStats& st, clock::time_point wall0, int64_t cpu0);
  bool stop_now();
  bool due(int every, int step) const { return every > 0 && step % every == 0; }
  void summarise();
  void write_final_state(double& depth, std::string& checksum);
  void write_report(double depth, const std::string& checksum);
  void drape_figures_on_root();  // collective
  void draw_picture();           // collective

  // The program's (the one-rank constructor leaves them as they are).
  clock::time_point t0_ = clock::now();
  MPI_Comm comm_ = MPI_COMM_SELF;
  int rank_ = 0, ranks_ = 1, threads_ = 1;
  bool talk_ = false;  // rank 0, not quiet
  RunOptions opt_;
  Timers tm_;
  Decomposition dec_;  // one rank: every tile owned, no halo, no reducer
  LocalReducer local_red_;
  std::vector<Block> blocks_;  // this rank's tiles in the collective files
  std::unique_ptr<Hdf5Output> h5_;
  std::optional<Progress> progress_;
  Summary sum_;
  // Grid sequencing: the uniform mesh's level now (0: finest, or off); the
  // run started on a coarser mesh (or its checkpoint was on one).
  int sequence_level_ = 0;
  bool sequencing_ = false;
  double finest_force_scale_ = 0;
  double ease_until_ = 0;  // stretched edges eased by the last split relax until this time
  // A restart's, until set up: its eased edges (pair slots) and digest sums per tile.
  std::vector<double> restart_eased_;
  std::vector<uint64_t> restart_tile_sums_;
  clock::time_point stage_start_;
  StageTime stage_before_;  // the previous stage's wall seconds and preconditioner
  int last_frame_ = -1;       // the step of the last frame written (-1: none yet)
  int last_checkpoint_ = -1;
  // Code of an agreed stop request: 2 * signal + wall budget.
  int stop_code_ = 0;
  int poison_ = 0, poison_rank_ = -1;  // fault injection (simulation_run.cpp)
  LoopClock clock0_;
  clock::time_point stepping0_;
};

}  // namespace drape
