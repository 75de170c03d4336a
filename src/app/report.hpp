#pragma once
// The run's figures: the paper's Table 2 columns, the decomposition's
// figures, the running summary, report.json and rank 0's closing tables.
#include <mpi.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "decomp/decomposition.hpp"
#include "decomp/rebalance.hpp"
#include "io/checkpoint.hpp"
#include "solver/drape_coefficient.hpp"
#include "solver/fabric.hpp"
#include "solver/loops.hpp"
#include "solver/model.hpp"
#include "solver/scene.hpp"
#include "solver/time_loop.hpp"
#include "solver/timers.hpp"
#include "solver/zigzag.hpp"

namespace drape {

// The paper's Table 2 columns for this run's time stepping: the time outside
// the parallel loops (sequential overhead), the time inside them beyond the
// busy thread time divided by the threads (parallel overhead: imbalance and
// synchronisation), and the speed-up this implies over one thread running
// the same busy work plus the sequential part.
struct Table2 {
  double time = 0, sequential = 0, parallel = 0, speedup = 1;
};


struct Summary {
  RunCounters counters;  // carried across restarts
  bool at_rest = false;
  bool stopped_by_wall_limit = false;
  int signal = 0;        // the signal that ended the run (0: none)
  int first_step = 0;    // the restart's step, 0 for a fresh run
  std::string checkpoint;  // the last checkpoint written, "" if none
  Table2 table2;
  StepStats last;
  DecompStats decomp;
  int64_t active_min = 0, active_max = 0, active_final = 0;  // active particles
  double total_mass = 0;  // kg, by tile over the ranks (total_mass in solver/model.hpp)
  int64_t refined = 0, coarsened = 0;                         // AMRC operations
  int64_t refined_inside = 0;  // of `refined`, leaves split for cutting into the obstacle
  int64_t refined_near = 0;    // of `refined`, leaves split for another part of the cloth nearby (self-contact)
  std::vector<Rebalance> rebalances;                          // after AMRC, several ranks
  // Grid sequencing: where each uniform mesh took over, and what its steps
  // cost in this process (what limits its dt: Newton iterations, retries,
  // contact halvings, multigrid builds).
  struct Stage {
    int step;
    double time;
    int level;
    int64_t particles;
    const char* preconditioner = "";  // Newton's on this mesh ("auto" resolved), "none" with nonlinear CG
    int64_t steps = 0, newton = 0, linear = 0, evaluations = 0;
    int64_t retries = 0, contact_halvings = 0, multigrid_builds = 0, rest_guesses = 0;
    double seconds = 0, cpu_seconds = 0;  // wall and this process's CPU time of its steps
    void add(const StepStats& st, double wall, double cpu) {
      ++steps;
      newton += st.newton_iterations;
      linear += st.iterations;
      evaluations += st.evaluations;
      retries += st.retries;
      contact_halvings += st.contact_halvings;
      multigrid_builds += st.multigrid_builds;
      rest_guesses += st.rest_guess;
      seconds += wall;
      cpu_seconds += cpu;
    }
  };
  std::vector<Stage> stages;
  int final_level = 0;              // grid sequencing: the level the run ended on (0: the finest, or AMRC)
  bool sequence_cut_short = false;  // at rest on a coarser mesh, with no time left for a finer one
  Zigzag zigzag;                    // kinks at the mesh spacing in the final state
  double penetration_written = 0;  // m: max_penetration_written of the final frame
  DrapeTest drape;                 // the drape test's figures (rank 0's; a drape test's scene)
  int64_t picture_positions = 0;   // the positions rank 0 received to draw the picture
  std::vector<MultigridLevelStats> multigrid;  // the last mesh's levels (none with jacobi)
  // Bytes gathered into each rank for the multigrid (0 on one rank): K's
  // rows or level 1's and the power iteration's vectors at the last build and a V-cycle's right-hand side, and their sums
  // over this process's builds and V-cycles; the builds (either way).
  struct Gathered {
    int64_t build = 0, cycle = 0, builds = 0, cycles = 0, build_count = 0;
    double cpu_max = 0, cpu_sum = 0;  // CPU seconds in the V-cycles: the largest rank's, all ranks together
    double build_cpu_max = 0, build_cpu_sum = 0;  // CPU seconds in the builds, the same way
  } multigrid_gathered;
  // What the run solved (report.json and the closing line).
  bool sequencing = false;    // grid sequencing was on (coarse uniform meshes first)
  double drag = 0;            // 1/s: the air drag the final mesh's steps ran with
  uint64_t pair_builds = 0;   // self-contact: times the pair list was built
  int64_t pairs_listed = 0;   // self-contact: pairs in the last list (each counted at both particles)
  double pair_distance = 0;   // self-contact: the pair distance D of the final mesh
  double closest_pair = HUGE_VAL;  // self-contact: the least distance between listed partners at the end
  int64_t contact_ghosts = 0; // self-contact: other ranks' particles hashed at the last build, over ranks
  double final_spacing = 0;   // m: the final mesh's spacing, the larger of warp and weft
                              // (with AMRC, the finest leaf's)
  int64_t peak_rss = 0;             // bytes: the largest of the ranks' peak resident sets
  int64_t estimated_rss = 0;        // bytes a rank, as estimated before the start (check_memory)
};

// The linear solve's preconditioner: Newton's CG has solver.preconditioner
// (jacobi or multigrid), the paper's nonlinear CG none.
const char* preconditioner_name(const SolverSpec& s);
// The spacing of a uniform mesh `level` levels above the grid's (m).
double level_spacing(const Grid& g, int level);
// One line for the picture: the scene, the grid, the mesh solved (its level
// when coarser than the grid, its particles and spacing), the method and
// preconditioner, the drag, the simulated time and whether at rest, and the
// unconverged steps if any. ASCII only.
std::string what_was_solved(const Scene& scene, const Cloth& cloth, const Summary& s, int64_t particles_solved);

Table2 table2(const LoopClock& a, const LoopClock& b, double time, int threads);
int64_t active_particles(const Cloth& c);
// Collective (the reducer's max).
double max_penetration(const Cloth& c, const Model& m, const ActiveLists& lists, const Reducer& red);
// The same over every particle of this rank's tiles as written (inactive ones
// filled in on their leaves): what the output's surface does. Collective.
double max_penetration_written(const Cloth& c, const Model& m, const Tiling& tiling, const std::vector<int>& owned,
                               const Reducer& red);
// This process's CPU time so far (user + system, all its threads), in µs:
// beside the wall time, it times a run that shared its cores with others.
int64_t process_cpu_microseconds();
// This process's peak resident set so far, in bytes (getrusage's ru_maxrss).
int64_t peak_rss_bytes();
// cpu: the CPU seconds of all ranks together.
std::string report_json(const Scene& scene, const Fabric& fabric, const Cloth& cloth,
                        const Summary& s, const Timers& tm, double wall, double cpu, int ranks, int threads,
                        const std::string& checksum, double penetration_depth, int64_t free_particles);
void print_table2(const Table2& t, int threads);
// peak_rss: bytes, the largest rank's; gathered: the multigrid's on several ranks (a line where not 0).
void print_timing_table(const Timers& tm, double wall, double cpu, const std::string& checksum, const DecompStats& d,
                        int ranks, int64_t peak_rss, const Summary::Gathered& gathered = {});

}  // namespace drape
