// The scene's keys: one declaration each, binding the TOML key to its Scene
// member with unit, allowed values, the comment --dry-run prints and the
// reference's meaning, and an example value other than the default (the
// tests set it and expect that key's member, and no other, to change). A new
// key is a member in solver/scene.hpp and a declaration here; checks that
// involve two keys are in config.cpp's validate().
// The order is the order of --dry-run's text and of the reference.
#include "io/scene_schema.hpp"

namespace drape {
namespace {

void declare_cloth(ParameterList& list) {
  list.section("cloth", &Scene::cloth)
      .add("particles", &ClothSpec::particles, "", each_of("NI and NJ", at_least(3)), "NI (warp), NJ (weft)",
           "NI (warp, i) × NJ (weft, j) particles of the finest grid").example("[999, 1000]")
      .add("size", &ClothSpec::size, "m", all_of("sizes", positive()), "m along i, j",
           "along i and j; rest spacing h = size / (N − 1)").example("[1.0, 0.9]")
      .add("fabric", &ClothSpec::fabric, "", non_empty(), "name in data/kes/ or a path",
           "a fabric in `data/kes/` by name (or `$DRAPE_DATA/kes`), or a path to a `.toml`")
          .example("other-fabric")
      .add("tile", &ClothSpec::tile, "", at_least(2), "particles per tile side",
           "particles per tile side: the unit of ownership, partitioning and migration across ranks; "
           "at most as many ranks as tiles").example("40")
      .add("shear", &ClothSpec::shear, "", any(), "KES shear band",
           "the KES shear band (G, 2HG); `false` leaves shear free").example("false")
      .add("clamp", &ClothSpec::clamp, "", any(), "rows i < clamp held fixed (a platform); 0: none",
           "rows i < clamp held fixed (a platform, Peirce's test); in [0, NI)").example("1")
      .add("bend_reversal", &ClothSpec::bend_reversal, "", zero_or(above(1), "the band taken literally"),
           "slope inside the bending band / loading slope (0 literal band, > 1 KES reversal)",
           "slope of the moment inside the KES bending band, as a multiple of the band's: 0 is the band "
           "taken literally, whose loop runs backwards and feeds the cloth energy; > 1 crosses the band "
           "and dissipates, as measured loops do").example("4.0")
      .add("shear_reversal", &ClothSpec::shear_reversal, "", zero_or(above(1), "the band taken literally"),
           "the same for shear", "the same for the shear band").example("4.0")
      .add("stretch_reversal", &ClothSpec::stretch_reversal, "", zero_or(at_least(1), "the band taken literally"),
           "stretch: the same (1: along the loading curve's slope)",
           "the same for stretch (1 moves along the loading curve)").example("4.0")
      .add("compression", &ClothSpec::compression, "", in_closed(0, 1),
           "compressive modulus / the tensile test's Fm/EMT (0: no resistance)",
           "in-plane compression, which KES does not measure: a branch reaching this fraction of the "
           "tensile test's Fm/EMT over EMT/2 of shortening; 0 carries no force, and edges may collapse "
           "where the cloth gathers").example("0.2")
      .add("height", &ClothSpec::height, "m", any(), "m, z of the flat cloth at t = 0",
           "z of the flat cloth at t = 0 (the default box's top is at 0.4); ≥ 0 when there is a floor")
          .example("0.5")
      .add("center", &ClothSpec::center, "m", any(), "m, x-y of the cloth centre", "x-y of the cloth's centre")
          .example("[0.1, 0.0]")
      .add("shape", &ClothSpec::shape, {ClothShape::Square, ClothShape::Disc}, "square | disc (the inscribed circle)",
           "`disc`: the circular specimen of a drape test, the grid's cells whose centres lie within size/2 of "
           "the centre; the other particles are removed. Needs equal sizes and `amrc.enabled = false`; runs on the finest "
           "mesh (no grid sequencing); with an `obstacle.shape = \"disc\"`, report.json gives the "
           "`drape_coefficient`").example("disc");
}

void declare_obstacle(ParameterList& list) {
  list.section("obstacle", &Scene::obstacle)
      .add("shape", &ObstacleSpec::shape, {ObstacleShape::Box, ObstacleShape::Sphere, ObstacleShape::None, ObstacleShape::Disc},
           "box | sphere | none | disc", "what the cloth falls on (besides the floor); `disc`: a vertical "
           "cylinder of `radius` and height size[2] about `center` (a drape tester's support disc)")
          .example("sphere")
      .add("center", &ObstacleSpec::center, "m", any(), "m", "the box's (sphere's, disc's) centre")
          .example("[0.0, 0.0, 0.3]")
      .add("size", &ObstacleSpec::size, "m", all_of("sizes", positive()), "m, box edge lengths",
           "the box's edge lengths along x, y, z; a disc's thickness is the z one").example("[0.4, 0.4, 0.3]")
      .add("radius", &ObstacleSpec::radius, "m", positive(), "m, sphere or disc", "the sphere's (or disc's) radius")
          .example("0.3")
      .add("floor", &ObstacleSpec::floor, "", any(), "plane z = 0", "a floor plane at z = 0").example("false")
      .add("friction", &ObstacleSpec::friction, "", non_negative(), "Coulomb mu on the box, sphere or disc (0: none)",
           "Coulomb friction coefficient μ between cloth and the box, sphere or disc (one μ, static and kinetic); "
           "0 is frictionless. The default is denim's measured coefficient ([validation.md]"
           "(validation.md#friction-coefficients))").example("0.5")
      .add("floor_friction", &ObstacleSpec::floor_friction, "", non_negative(), "Coulomb mu on the floor (0: none)",
           "Coulomb friction coefficient μ between cloth and the floor; 0 is frictionless. The default as "
           "`obstacle.friction`'s").example("0.5");
}

void declare_solver(ParameterList& list) {
  list.section("solver", &Scene::solver)
      .add("dt", &SolverSpec::dt, "s", positive(), "s, first step (adaptive afterwards)",
           "the first time step; adapted afterwards to keep iterations per step bounded, within "
           "[dt_min, dt_max]").example("0.002")
      .add("dt_min", &SolverSpec::dt_min, "s", positive(), "s",
           "a step that has not converged at this dt (or after 8 halvings) is accepted as unconverged "
           "(`unconverged_steps`)").example("2e-05")
      .add("dt_max", &SolverSpec::dt_max, "s", positive(), "s", "the longest time step; ≥ dt_min").example("0.005")
      .add("steps", &SolverSpec::steps, "", at_least(1), "time steps at most",
           "time steps at most; rest, `end_time` or `wall_limit` usually ends the run first").example("10")
      .add("max_iterations", &SolverSpec::max_iterations, "", at_least(1), "CG iterations per step at most",
           "CG iterations per step attempt at most; a step that reaches it is retried with half the step")
          .example("100")
      .add("tolerance", &SolverSpec::tolerance, "", positive(), "cost per active particle",
           "a step has converged when the cost per free particle is below this").example("1e-07")
      .add("gradient", &SolverSpec::gradient, {GradientMode::Analytic, GradientMode::Numeric},
           "analytic | numeric", "`numeric`: finite differences, the paper's way (one rank only, no AMRC)")
          .example("numeric")
      .add("method", &SolverSpec::method, {SolverMethod::Newton, SolverMethod::Cg},
           "newton (Newton + linear CG) | cg (the paper's nonlinear CG)",
           "`newton`: Newton steps on the force balance, each solved by preconditioned linear CG; `cg`: "
           "the paper's nonlinear CG on the total cost. Both stop at the same cost "
           "([design.md §6](design.md#6-solvers-the-cost-is-stiff))").example("cg")
      .add("preconditioner", &SolverSpec::preconditioner,
           {Preconditioner::Jacobi, Preconditioner::Multigrid, Preconditioner::Auto},
           "newton's linear CG: jacobi | multigrid | auto",
           "Newton's linear CG: `jacobi` (each particle's diagonal) or `multigrid` (a V-cycle over the "
           "grid's levels: 20x fewer iterations than Jacobi at 513 x 513, growing 3.9x from 65 to 513 against Jacobi's 9.5x; "
           "on several ranks the levels are built from all ranks' rows on every rank alike, the finest level's "
           "sweeps run on each rank's own rows and the coarser levels on every rank, bitwise one rank's result, self-contact's blocks across ranks and AMRC's hanging particles included) "
           "([design.md §7](design.md)); `auto`: "
           "each mesh (grid sequencing's stages; with AMRC, the mesh after each adaptation) takes the multigrid "
           "from `multigrid_particles` active particles on, Jacobi below it")
          .example("multigrid")
      .add("multigrid_particles", &SolverSpec::multigrid_particles, "", at_least(1),
           "auto: active particles from which a mesh takes the multigrid",
           "with `preconditioner = \"auto\"`, a mesh of at least this many active particles is solved with "
           "the multigrid, a smaller one with Jacobi ([performance.md](performance.md#what-limits-dt-in-the-time-loop))")
          .example("4000")
      .add("multigrid_dt_max", &SolverSpec::multigrid_dt_max, "s", positive(),
           "auto: dt_max on the meshes that take the multigrid",
           "with `preconditioner = \"auto\"`, the meshes solved with the multigrid step up to this (their dt "
           "follows Newton's iteration count, `newton_target`); Jacobi's keep `dt_max`").example("0.02")
      .add("multigrid_max_iterations", &SolverSpec::multigrid_max_iterations, "", at_least(1),
           "auto: max_iterations on the meshes that take the multigrid",
           "with `preconditioner = \"auto\"`, a step on a multigrid mesh may take this many linear CG iterations "
           "(a long step's Newton iterations need them); Jacobi's meshes keep `max_iterations`, which their dt "
           "rule reads").example("500")
      .add("prediction", &SolverSpec::prediction, {Prediction::Fall, Prediction::Rest, Prediction::Cheaper},
           "newton: a step's first guess: fall | rest | cheaper",
           "a Newton step's first guess: the last step's motion carried on, with gravity's free fall added "
           "(`fall`: exact for a falling cloth) or not (`rest`: exact for a cloth at rest, where the fall "
           "would press g dt^2 into the contact layer and the edges holding the hanging sides); `cheaper`: "
           "whichever of the two has the lower cost, one evaluation more a step "
           "([design.md §6](design.md#6-solvers-the-cost-is-stiff)); the nonlinear CG takes `fall`")
          .example("fall")
      .add("newton_target", &SolverSpec::newton_target, "", at_least(1),
           "multigrid: Newton iterations per step that dt grows under",
           "with `preconditioner = \"multigrid\"`, dt grows (×1.25) after a step of at most this many Newton "
           "iterations and shrinks (×0.7) above 1.5 times it, after a retry, or past max_iterations/2 linear "
           "iterations ([design.md §6](design.md#6-solvers-the-cost-is-stiff)); with `jacobi` the linear "
           "iterations choose dt").example("8")
      .add("multigrid_divided", &SolverSpec::multigrid_divided, "", any(),
           "multigrid, several ranks: the finest level on each rank's rows",
           "with the multigrid on several ranks, each rank runs the V-cycle's finest level (its sweeps, residual "
           "and restriction) on its own rows of K, exchanging the few entries of other ranks' rows they read, and "
           "gathers level 1's right-hand side only; false: every rank gathers the whole right-hand side and runs "
           "the whole cycle (the reference: the same result bit for bit, more work a rank) "
           "([design.md §7](design.md))").example("false")
      .add("slope_line_search", &SolverSpec::slope_line_search, "", any(),
           "newton: line search on the energy slope (else backtracking)",
           "Newton's line search: regula falsi on the slope of the step's energy along the direction, "
           "which finds where a step that crosses the hysteresis bands' kinks stops descending; false: "
           "halving from the full step until the cost decreases "
           "([design.md §6](design.md#6-solvers-the-cost-is-stiff))").example("false")
      .add("adaptive_forcing", &SolverSpec::adaptive_forcing, "", any(),
           "newton: linear tolerance from the residual's last reduction",
           "Newton's linear solves stop at a relative tolerance of 0.9 times the square of the last Newton "
           "iteration's residual reduction (Eisenstat-Walker), within [0.001, 0.9] and never tighter than "
           "reaching `tolerance` needs: fewer linear iterations through the bands' kinks; "
           "false: the residual's root mean square in particle weights, within [0.001, 0.1] "
           "([design.md §6](design.md#6-solvers-the-cost-is-stiff))").example("true")
      .add("band_active_set", &SolverSpec::band_active_set, "", any(),
           "newton: re-solve with the band branches a full step lands on",
           "Newton through the hysteresis bands' kinks: when the full step's energy slope is not within a "
           "quarter of the slope at the start, the elements whose band branch (upper edge, lower edge, "
           "inside) the step changed take the secant of their force as stiffness and the step is solved "
           "again from the same point, at most twice, before the line search "
           "([design.md §6](design.md#6-solvers-the-cost-is-stiff))").example("true")
      .add("damping", &SolverSpec::damping, "", in_half_open(0, 1), "fraction of velocity removed per step",
           "fraction of the velocity removed after each step").example("0.1")
      .add("rest_speed", &SolverSpec::rest_speed, "m/s", non_negative(), "m/s; > 0 stops once at rest",
           "> 0 ends the run once every particle is slower for 3 steps (and at least 2·rest_speed/g of "
           "time); with friction on, slower than 3 friction slips a step where that is faster (held cloth "
           "creeps); 0: never at rest").example("0.02")
      .add("contact_thickness", &SolverSpec::contact_thickness, "m", non_negative().with_note("0: automatic"),
           "m; 0 = automatic", "the contact layer; 0: half the grid spacing (a coarse mesh of grid sequencing: half its cell diagonal), or half the fabric's thickness if larger")
          .example("0.001")
      .add("self_contact", &SolverSpec::self_contact, "", any(),
           "cloth-cloth contact",
           "cloth-cloth contact: two particles that are not mesh neighbours keep twice the contact layer "
           "apart ([design.md §1](design.md#1-the-cloth-model)) on any number of ranks; with AMRC, leaves "
           "near another part of the cloth split to the finest level "
           "([design.md §2](design.md#2-amrc-and-grid-sequencing)); needs `solver.gradient = \"analytic\"`: false "
           "for the numeric one").example("false")
      .add("memory", &SolverSpec::memory, "", non_negative(), "weight of the force memory (hysteresis) term",
           "weight of the memory term that pulls each force to its hysteresis target").example("0.5")
      .add("drag", &SolverSpec::drag, "1/s", non_negative(), "1/s: air drag, a force -drag*m*v on each particle",
           "air drag −drag·m·v in each particle's equation; with grid sequencing on, every mesh runs with "
           "max(drag, `amrc.stage_drag`)").example("1.0")
      .add("wall_limit", &SolverSpec::wall_limit, "s", non_negative().with_note("0: no limit"),
           "s; stop stepping after this long (0: no limit)",
           "wall time of stepping at most; the run then ends cleanly with a checkpoint").example("60.0")
      .add("end_time", &SolverSpec::end_time, "s", non_negative().with_note("0: no limit"),
           "s of simulated time; stop once reached (0: no limit)", "simulated time at most").example("1.0");
}

void declare_output(ParameterList& list) {
  list.section("output", &Scene::output)
      .add("every", &OutputSpec::every, "", non_negative(), "frame every N steps (0: final only)",
           "a frame in `drape.h5` every N steps (0: the final state only); at 1000 × 1000 a frame is 67 MB")
          .example("10")
      .add("picture", &OutputSpec::picture, "", any(), "drape.png of the final state",
           "`drape.png` of the final state").example("false")
      .add("checkpoint_every", &OutputSpec::checkpoint_every, "",
           non_negative().with_note("0: only on a signal or the wall limit"),
           "checkpoint.h5 every N steps and at the end (0: on a signal or the wall limit only)",
           "`checkpoint.h5` every N steps and at the end").example("5");
}

void declare_parallel(ParameterList& list) {
  list.section("parallel", &Scene::parallel)
      .add("schedule", &ParallelSpec::schedule,
           {Schedule::ActiveLists, Schedule::Static, Schedule::Dynamic, Schedule::Guided},
           "active-lists | static | dynamic | guided",
           "`active-lists` (the paper's), or a `static`, `dynamic` or `guided` schedule over tiles")
          .example("static")
      .add("chunk", &ParallelSpec::chunk, "", at_least(1), "tiles per chunk (dynamic schedule)",
           "tiles per chunk for the dynamic schedule").example("8")
      .add("threads", &ParallelSpec::threads, "", in_closed(0, 1024).with_note("0: OpenMP default"),
           "0: OMP_NUM_THREADS / OpenMP default",
           "OpenMP threads per rank; 0: `OMP_NUM_THREADS` (or `--threads`)").example("2")
      .add("imbalance", &ParallelSpec::imbalance, "", at_least(1).with_note("max / mean work per rank"),
           "max / mean work per rank that triggers a rebalance after AMRC",
           "after a mesh change, max/mean work per rank above which tiles move").example("1.2");
}

void declare_amrc(ParameterList& list) {
  list.section("amrc", &Scene::amrc)
      .add("enabled", &AmrcSpec::enabled, "", any(), "adaptive refinement and coarsening",
           "adaptive refinement and coarsening ([design.md §2](design.md#2-amrc-and-grid-sequencing))")
          .example("true")
      .add("max_level", &AmrcSpec::max_level, "", in_closed(0, 10), "coarsest leaves span 2^max_level intervals",
           "coarsest leaves span 2^max_level intervals").example("2")
      .add("refine", &AmrcSpec::refine, "rad", positive().with_note("rad"), "rad: split where a triple turns more",
           "a leaf splits where a mesh line turns more at one of its triples").example("0.2")
      .add("coarsen", &AmrcSpec::coarsen, "rad", any(), "rad: merge where all turn less (< refine)",
           "four children merge where all turn less; in [0, refine)").example("0.01")
      .add("every", &AmrcSpec::every, "", at_least(1), "steps between adaptations", "steps between adaptations")
          .example("5")
      .add("coarsen_speed", &AmrcSpec::coarsen_speed, "m/s", non_negative().with_note("m/s; 0: no speed condition"),
           "m/s: merge only where all are slower (0: off)",
           "children merge only where every particle is also slower; 0: off (the paper's criterion)")
          .example("0.05")
      .add("indicator", &AmrcSpec::indicator, {AmrcIndicator::Angle, AmrcIndicator::Deflection},
           "angle | deflection (the angle times the leaf's width over the coarsest's)",
           "`angle`: thresholds against the turning angle; `deflection`: against the angle times the "
           "leaf's width over the coarsest leaf's").example("deflection")
      .add("start_spacing", &AmrcSpec::start_spacing, "m",
           non_negative().with_note("m; 0: the run starts on the finest mesh"),
           "m: start this coarse (AMRC: leaves this wide; else refine at each rest); 0: finest",
           "AMRC off: grid sequencing, the run starts on a uniform mesh at most this coarse and refines "
           "everywhere each time the cloth is at rest; AMRC on: every leaf starts this wide (at most "
           "`max_level`)").example("0.0")
      .add("stage_drag", &AmrcSpec::stage_drag, "1/s", non_negative().with_note("1/s"),
           "1/s: air drag on every mesh while grid sequencing",
           "air drag on every mesh while grid sequencing (the meshes lead to the rest state, and drag "
           "vanishes at rest, but with the hysteresis bands the rest state remembers the path the drag "
           "damped: [performance.md](performance.md#what-limits-dt-in-the-time-loop)); `report.json` "
           "`stage_drag`").example("5.0")
      .add("last_level", &AmrcSpec::last_level, "", non_negative(),
           "grid sequencing ends at rest on this level; 0: the finest",
           "AMRC off: the run ends at rest on the uniform mesh of this level (the finest mesh's spacing "
           "times 2^level) instead of refining further; 0: refine to the finest").example("3");
}

ParameterList declare() {
  ParameterList list;
  list.top().add("name", &Scene::name, "", non_empty(), "", "the scene's name, in the output").example("other");
  declare_cloth(list);
  declare_obstacle(list);
  declare_solver(list);
  declare_output(list);
  declare_parallel(list);
  declare_amrc(list);
  return list;
}

}  // namespace

const ParameterList& scene_parameters() {
  static const ParameterList list = declare();
  return list;
}

}  // namespace drape
