#pragma once
// The scene a run simulates: plain data, SI units, already validated.
// src/io/config.cpp fills it from TOML; the solver only reads it.
#include <array>
#include <cstdint>
#include <string>

namespace drape {

// Disc: a flat vertical cylinder (the Cusick drape tester's support disc).
enum class ObstacleShape { Box, Sphere, None, Disc };
// The specimen's outline: the whole grid, or the disc inscribed in it
// (particles outside are removed, the Cusick test's circular specimen).
enum class ClothShape { Square, Disc };
enum class GradientMode { Analytic, Numeric };
enum class Schedule { ActiveLists, Static, Dynamic, Guided };
enum class SolverMethod { Newton, Cg };
// The Newton step's linear solve: CG preconditioned by the stiffness's
// diagonal, or by a multigrid V-cycle over the grid's levels (one rank).
enum class Preconditioner { Jacobi, Multigrid, Auto };
// A Newton step's first guess: the history moved on with its velocity and
// gravity's free fall added (fall), not added (rest: exact for a cloth at
// rest), or whichever of the two costs less (cheaper).
enum class Prediction { Fall, Rest, Cheaper };
// What AMRC's thresholds are compared with (AmrcSpec::indicator).
enum class AmrcIndicator { Angle, Deflection };

struct ClothSpec {
  std::array<int, 2> particles{1000, 1000};  // NI (warp, i) x NJ (weft, j)
  std::array<double, 2> size{1.0, 1.0};      // m along i and j
  std::string fabric = "denim-A";            // name in data/kes/ or a path
  int tile = 50;                             // particles per tile side
  bool shear = true;                         // KES shear band on/off
  double height = 0.45;                      // m, z of the flat cloth at t = 0
  std::array<double, 2> center{0.0, 0.0};    // m, x-y of the cloth centre
  ClothShape shape = ClothShape::Square;     // disc: only the particles within size/2 of the centre
  int clamp = 0;                             // rows i < clamp held fixed (a platform)
  // Slope of the force inside a KES band, as a multiple of the loading
  // curve's (Band::set_reversal), per kind of band. 0 is the band taken
  // literally, whose loop runs backwards and feeds the cloth energy; > 1
  // dissipates as a KES loop does.
  double bend_reversal = 5;
  double shear_reversal = 5;
  double stretch_reversal = 5;
  // In-plane compression: woven cloth buckles out of its plane rather than
  // shorten its yarns, which KES does not measure. A branch of this fraction
  // of the tensile test's mean modulus Fm/EMT (0: edges may collapse).
  double compression = 0.1;
};

struct ObstacleSpec {
  ObstacleShape shape = ObstacleShape::Box;
  std::array<double, 3> center{0.0, 0.0, 0.2};  // m
  std::array<double, 3> size{0.4, 0.4, 0.4};    // m, box edge lengths (disc: size[2] its thickness)
  double radius = 0.2;                          // m, sphere or disc
  bool floor = true;                            // plane z = 0
  // Coulomb mu, on by default: denim's measured coefficient (docs/validation.md,
  // "Friction coefficients"); 0 is frictionless.
  double friction = 0.3;                        // cloth on the box, sphere or disc
  double floor_friction = 0.3;                  // cloth on the floor
};

struct SolverSpec {
  double dt = 1e-3;             // s, first step (adaptive afterwards)
  double dt_min = 1e-5;         // s
  double dt_max = 4e-3;         // s
  int steps = 100000;           // time steps at most (the wall limit or rest ends a run first)
  int max_iterations = 200;     // CG iterations per step at most
  double tolerance = 1e-6;      // converged when cost per active particle < this
  GradientMode gradient = GradientMode::Analytic;
  // newton: Newton steps solved by linear CG (fast); cg: the paper's nonlinear
  // CG on the total cost. Both stop when the same cost is below tolerance.
  SolverMethod method = SolverMethod::Newton;
  // auto: the multigrid on fine meshes, Jacobi on coarse ones and with AMRC.
  Preconditioner preconditioner = Preconditioner::Auto;
  // auto: a mesh with at least this many active particles takes the
  // multigrid (the default run's meshes from level 5's 1089 on, where it
  // reaches rest on less CPU than Jacobi)
  int multigrid_particles = 1000;
  double multigrid_dt_max = 0.05;   // s, auto: dt_max on the multigrid's meshes (its dt follows Newton's count)
  int multigrid_max_iterations = 1000;  // auto: max_iterations on the multigrid's meshes
  Prediction prediction = Prediction::Cheaper;  // Newton: a step's first guess (nonlinear CG: fall)
  int newton_target = 16;       // multigrid: dt grows while a step takes at most this many Newton iterations
  bool multigrid_divided = true;  // several ranks: the V-cycle's finest level on each rank's rows (else gathered whole)
  bool slope_line_search = true;  // Newton's line search on the energy slope (else backtracking on the cost)
  bool adaptive_forcing = false;  // Newton: linear tolerance from the residual's last reduction (Eisenstat-Walker)
  bool band_active_set = false;  // Newton: re-solve a step with the tangent of the band branches it lands on
  double damping = 0.0;         // fraction of velocity removed per step, [0, 1)
  double drag = 0.0;            // 1/s: air drag -drag*m*v in each particle's Newton equation
  double rest_speed = 0.01;     // m/s; > 0 ends the run once max speed is below it (3 steps)
  double contact_thickness = 0.0;  // m; 0 = automatic (half the spacing; a coarse stage: half its cell diagonal)
  bool self_contact = true;     // cloth-cloth contact between particles that are not mesh neighbours
  // Weight of the memory term 1/2 mu |(f - f_history) lambda / F0|^2: inside a
  // KES band a force costs nothing, so without it the minimum is not unique;
  // with it each force is pulled to its hysteresis target (Band::stop): the
  // history force while inside the band, the band edge once pushed past it.
  double memory = 1.0;
  double wall_limit = 540.0;    // s of stepping at most (0: none); the run then ends cleanly
  double end_time = 0.0;        // s of simulated time at most (0: none)
};

struct OutputSpec {
  int every = 1000;             // write a frame every N steps (0: final only)
  bool picture = true;          // drape.png of the final state
  int checkpoint_every = 0;     // checkpoint.h5 every N steps and at the end (0: only on a signal or the wall limit)
};

struct ParallelSpec {
  Schedule schedule = Schedule::ActiveLists;
  int chunk = 4;                // tiles per chunk for the dynamic schedule
  int threads = 0;              // 0: OMP_NUM_THREADS / OpenMP default
  double imbalance = 1.05;      // max / mean work per rank above which AMRC's new mesh is repartitioned
};

// AMRC (docs/design.md §2): the criterion is the turning angle of the mesh at each
// triple (rad), the bending a leaf's elements resolve: a leaf splits where it
// exceeds `refine`, children merge where all stay below `coarsen`.
struct AmrcSpec {
  bool enabled = false;
  int max_level = 3;            // coarsest leaves span 2^max_level intervals
  double refine = 0.1;          // rad
  double coarsen = 0.02;        // rad, below refine so cells do not flip back and forth
  int every = 3;                // steps between adaptations
  // Children merge only where every particle is slower than this (m/s): the
  // impact is then met on the finest mesh, and the settled parts coarsen.
  // 0: no such condition (the paper's criterion).
  double coarsen_speed = 0;
  // angle: the turning angle itself, the same threshold on every level (the
  // paper's kind of criterion). deflection: the angle times the leaf's width
  // over the coarsest leaf's, so the thresholds read as angles at the coarsest
  // spacing and a leaf half as wide must turn twice as much to split: what a
  // leaf's flat surface misses grows with width x angle, and this spends the
  // particles where that is large.
  AmrcIndicator indicator = AmrcIndicator::Angle;
  // Grid sequencing (amrc.enabled = false): the run starts on a uniform
  // mesh of spacing at most this (m), and refines it everywhere by one level
  // each time the cloth comes to rest, until the finest; 0: from the finest.
  // With AMRC: a new run starts with every leaf that wide (at most
  // max_level) and adapts from there; 0: from the finest (the paper's).
  double start_spacing = 0.04;
  // Air drag (1/s) on those coarser meshes: they are the way to the rest
  // state, not the result, so they may settle faster than air would let
  // them (drag vanishes at rest, so it does not move the rest state). While
  // sequencing, every mesh, the finest included, runs with
  // max(solver.drag, stage_drag); without it, solver.drag applies.
  double stage_drag = 10.0;
  // Grid sequencing ends at rest on this level (0: the finest mesh): a
  // stage measured on its own, or a coarse drape kept as the result.
  int last_level = 0;
};

struct Scene {
  std::string name = "box-drape";
  ClothSpec cloth;
  ObstacleSpec obstacle;
  SolverSpec solver;
  OutputSpec output;
  ParallelSpec parallel;
  AmrcSpec amrc;
};

const char* to_string(ObstacleShape s);
const char* to_string(ClothShape s);
const char* to_string(GradientMode g);
const char* to_string(Schedule s);
const char* to_string(SolverMethod m);
const char* to_string(Preconditioner p);
const char* to_string(Prediction p);

// The preconditioner a mesh of `particles` active particles is solved
// with: `auto` takes the multigrid from solver.multigrid_particles on (its
// linear iterations barely grow as the spacing halves, Jacobi's double, and
// its longer steps pay for the builds only on fine meshes), Jacobi below
// (an AMRC mesh by its active particles after each adaptation);
// `jacobi` and `multigrid` as they are.
Preconditioner stage_preconditioner(const SolverSpec& s, int64_t particles);
// The solver settings for that mesh: `auto`'s multigrid meshes take
// multigrid_dt_max and multigrid_max_iterations (a step's linear budget
// must not cut the multigrid's long steps short; Jacobi's dt rule reads
// max_iterations, so its meshes keep theirs).
SolverSpec stage_solver(const SolverSpec& s, int64_t particles);
const char* to_string(AmrcIndicator i);

}  // namespace drape
