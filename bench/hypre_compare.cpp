// Newton's linear solve K x = b on the assembled stiffness, drape's own
// geometric multigrid against hypre's BoomerAMG (algebraic), each as the
// preconditioner of CG, from one drape state: the box drape at the finest
// mesh, stepped (Jacobi, fixed dt) to --time, b = -rho at the free particles.
// Per method: set-up and solve CPU seconds, iterations, and both in units of one
// stiffness product timed in the same run, so that the choice between the
// two is measured on this machine. One rank (hypre's IJ interface on
// MPI_COMM_WORLD), one thread (Debian's hypre is built without OpenMP).
// Figures: docs/performance.md (raw output in docs/data/hypre-compare/).
//   hypre_compare [--size 129] [--time 0.12] [--dt 5e-4] [--tol 1e-6] [--max-iterations 1000]
//                 [--repeat 1] [--only NAME-PART] [--json FILE]
#include <mpi.h>
#include <omp.h>

#include <HYPRE.h>
#include <HYPRE_krylov.h>
#include <HYPRE_parcsr_ls.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "io/json.hpp"
#include "landing_state.hpp"

namespace drape {
namespace {

struct Result {
  std::string name;
  int iterations = 0;
  bool converged = false;
  double setup = 0, solve = 0;  // CPU seconds (best of --repeat)
  double wall = 0;              // wall-clock seconds of set-up and solve (best of --repeat)
  double residual = 0;          // true |b - K x| / |b|
  double total() const { return setup + solve; }
};

// This thread's CPU seconds: the machine may be shared, and wall-clock
// times of the same solve varied twofold there; every solve here runs on
// this one thread (OpenMP set to 1, hypre built without it).
double dot(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0;
  for (size_t k = 0; k < a.size(); ++k) s += a[k] * b[k];
  return s;
}

double true_residual(const BlockMatrix& K, const std::vector<double>& b, const std::vector<double>& x) {
  std::vector<double> r(b.size());
  K.residual(b.data(), x.data(), r.data());
  return std::sqrt(dot(r, r) / dot(b, b));
}

// CG preconditioned by one V-cycle of drape's multigrid, on the assembled K
// (the products hypre's CG does too, so the two differ in the preconditioner).
Result multigrid_solve(const MultigridSettings& settings, const std::string& name, const BlockMatrix& K,
                       const std::vector<int64_t>& ids, int n, const std::vector<double>& b, double tol, int max_it) {
  Result res{name};
  const size_t m = b.size();
  // A fresh object: the set-up timed is the whole one (patterns and values),
  // as for hypre's.
  Multigrid mg(settings);
  const double w0 = omp_get_wtime();
  double t0 = cpu_seconds();
  mg.setup(K, ids, n, n, 1);
  res.setup = cpu_seconds() - t0;
  t0 = cpu_seconds();
  std::vector<double> x(m, 0.0), r = b, z(m), p(m), q(m);
  const double target = tol * tol * dot(b, b);
  mg.apply(r.data(), z.data());
  p = z;
  double rz = dot(r, z);
  int it = 0;
  while (it < max_it) {
    K.multiply(p.data(), q.data());
    const double a = rz / dot(p, q);
    double rr = 0;
    for (size_t k = 0; k < m; ++k) {
      x[k] += a * p[k];
      r[k] -= a * q[k];
      rr += r[k] * r[k];
    }
    ++it;
    if (rr <= target) {
      res.converged = true;
      break;
    }
    mg.apply(r.data(), z.data());
    const double rz1 = dot(r, z), beta = rz1 / rz;
    rz = rz1;
    for (size_t k = 0; k < m; ++k) p[k] = z[k] + beta * p[k];
  }
  res.solve = cpu_seconds() - t0;
  res.wall = omp_get_wtime() - w0;
  res.iterations = it;
  res.residual = true_residual(K, b, x);
  return res;
}

// One BoomerAMG configuration: its name and the calls that set it up.
struct AmgConfig {
  std::string name;
  std::function<void(HYPRE_Solver)> set;
  bool rotations = false;  // the rigid rotations as interpolation vectors
};

// CG (hypre's) preconditioned by one BoomerAMG V-cycle. The set-up timed
// includes copying K into hypre's IJ matrix: hypre needs its own copy.
// pos: the particles' positions about their centroid, 3 a row (the rigid
// rotations' vectors).
Result boomeramg_solve(const AmgConfig& cfg, const BlockMatrix& K, const std::vector<double>& b,
                       const std::vector<double>& pos, double tol, int max_it) {
  Result res{"boomeramg-" + cfg.name};
  const HYPRE_Int m = HYPRE_Int(b.size());
  const double w0 = omp_get_wtime();
  double t0 = cpu_seconds();
  // K's scalar rows, exact zeros of off-diagonal entries dropped (they would
  // only take part in BoomerAMG's strength tests as weak connections).
  std::vector<HYPRE_Int> ncols(m), rows(m), cols;
  std::vector<double> vals;
  cols.reserve(size_t(9) * K.blocks());
  vals.reserve(size_t(9) * K.blocks());
  for (int64_t br = 0; br < K.rows; ++br)
    for (int i = 0; i < 3; ++i) {
      const HYPRE_Int row = HYPRE_Int(3 * br + i);
      rows[row] = row;
      HYPRE_Int c = 0;
      for (int64_t e = K.start[br]; e < K.start[br + 1]; ++e)
        for (int j = 0; j < 3; ++j) {
          const double v = K.val[9 * e + entry(i, j)];
          const HYPRE_Int col = HYPRE_Int(3 * K.col[e] + j);
          if (v == 0 && col != row) continue;
          cols.push_back(col);
          vals.push_back(v);
          ++c;
        }
      ncols[row] = c;
    }
  HYPRE_IJMatrix A;
  HYPRE_IJMatrixCreate(MPI_COMM_WORLD, 0, m - 1, 0, m - 1, &A);
  HYPRE_IJMatrixSetObjectType(A, HYPRE_PARCSR);
  HYPRE_IJMatrixSetRowSizes(A, ncols.data());
  HYPRE_IJMatrixInitialize(A);
  HYPRE_IJMatrixSetValues(A, m, ncols.data(), rows.data(), cols.data(), vals.data());
  HYPRE_IJMatrixAssemble(A);
  HYPRE_ParCSRMatrix parA;
  HYPRE_IJMatrixGetObject(A, (void**)&parA);
  std::vector<double> zero(m, 0.0);
  HYPRE_IJVector bv, xv;
  for (HYPRE_IJVector* v : {&bv, &xv}) {
    HYPRE_IJVectorCreate(MPI_COMM_WORLD, 0, m - 1, v);
    HYPRE_IJVectorSetObjectType(*v, HYPRE_PARCSR);
    HYPRE_IJVectorInitialize(*v);
  }
  HYPRE_IJVectorSetValues(bv, m, rows.data(), b.data());
  HYPRE_IJVectorSetValues(xv, m, rows.data(), zero.data());
  HYPRE_IJVectorAssemble(bv);
  HYPRE_IJVectorAssemble(xv);
  HYPRE_ParVector parb, parx;
  HYPRE_IJVectorGetObject(bv, (void**)&parb);
  HYPRE_IJVectorGetObject(xv, (void**)&parx);

  HYPRE_Solver amg, pcg;
  HYPRE_BoomerAMGCreate(&amg);
  HYPRE_BoomerAMGSetPrintLevel(amg, 0);
  HYPRE_BoomerAMGSetMaxIter(amg, 1);  // one V-cycle a preconditioning
  HYPRE_BoomerAMGSetTol(amg, 0.0);
  cfg.set(amg);
  // Rotations about x, y and z: with the translations (one a function, which
  // nodal coarsening interpolates already) the near null space of a stiffness
  // without its mass term.
  std::vector<HYPRE_IJVector> rot;
  std::vector<HYPRE_ParVector> parrot;
  if (cfg.rotations) {
    std::vector<double> v(m);
    for (int a = 0; a < 3; ++a) {
      const int i = (a + 1) % 3, j = (a + 2) % 3;  // rotation about a: (e_a x p)
      for (HYPRE_Int r = 0; r < m / 3; ++r) {
        v[3 * r + a] = 0;
        v[3 * r + i] = -pos[3 * r + j];
        v[3 * r + j] = pos[3 * r + i];
      }
      HYPRE_IJVector iv;
      HYPRE_IJVectorCreate(MPI_COMM_WORLD, 0, m - 1, &iv);
      HYPRE_IJVectorSetObjectType(iv, HYPRE_PARCSR);
      HYPRE_IJVectorInitialize(iv);
      HYPRE_IJVectorSetValues(iv, m, rows.data(), v.data());
      HYPRE_IJVectorAssemble(iv);
      HYPRE_ParVector pv;
      HYPRE_IJVectorGetObject(iv, (void**)&pv);
      rot.push_back(iv);
      parrot.push_back(pv);
    }
    HYPRE_BoomerAMGSetInterpVectors(amg, HYPRE_Int(parrot.size()), parrot.data());
  }
  HYPRE_ParCSRPCGCreate(MPI_COMM_WORLD, &pcg);
  HYPRE_PCGSetTol(pcg, tol);
  HYPRE_PCGSetTwoNorm(pcg, 1);  // |r| / |b|, as drape's CG; the default is the preconditioned norm
  HYPRE_PCGSetMaxIter(pcg, max_it);
  HYPRE_PCGSetPrintLevel(pcg, 0);
  HYPRE_ParCSRPCGSetPrecond(pcg, HYPRE_BoomerAMGSolve, HYPRE_BoomerAMGSetup, amg);
  HYPRE_ParCSRPCGSetup(pcg, parA, parb, parx);
  res.setup = cpu_seconds() - t0;

  t0 = cpu_seconds();
  HYPRE_ParCSRPCGSolve(pcg, parA, parb, parx);
  res.solve = cpu_seconds() - t0;
  res.wall = omp_get_wtime() - w0;
  HYPRE_Int it = 0;
  HYPRE_PCGGetNumIterations(pcg, &it);
  res.iterations = int(it);
  std::vector<double> x(m);
  HYPRE_IJVectorGetValues(xv, m, rows.data(), x.data());
  res.residual = true_residual(K, b, x);
  res.converged = res.residual <= 1.01 * tol;  // hypre's own test is on its recursive residual

  HYPRE_ParCSRPCGDestroy(pcg);
  HYPRE_BoomerAMGDestroy(amg);
  for (HYPRE_IJVector iv : rot) HYPRE_IJVectorDestroy(iv);
  HYPRE_IJVectorDestroy(bv);
  HYPRE_IJVectorDestroy(xv);
  HYPRE_IJMatrixDestroy(A);
  return res;
}

// The configurations tried. hypre 2.26's defaults already are HMIS
// coarsening, extended+i interpolation (at most 4 entries a row) and
// hybrid Gauss-Seidel (symmetric over a V-cycle, as CG needs). The rest
// tell BoomerAMG that the unknowns come 3 to a particle (interleaved x, y,
// z: its default numbering of functions), coarsening by component
// ("unknown") or by particle ("nodal", the block norm of each 3 x 3 block),
// as suits elasticity-like operators; aggressive coarsening (agg: the first
// levels coarsened twice over, multipass interpolation) trades iterations
// for a cheaper hierarchy; cheb: Chebyshev smoothing, as drape's multigrid;
// rbm: the rigid rotations added to nodal interpolation (hypre's "GM
// variant 2", for elasticity), with ext+i or classical interpolation.
std::vector<AmgConfig> configs() {
  auto sys = [](HYPRE_Solver s) { HYPRE_BoomerAMGSetNumFunctions(s, 3); };
  return {
      {"default", [](HYPRE_Solver) {}},
      {"sys", sys},
      {"sys-pmis", [=](HYPRE_Solver s) { sys(s), HYPRE_BoomerAMGSetCoarsenType(s, 8); }},
      {"sys-st0.5", [=](HYPRE_Solver s) { sys(s), HYPRE_BoomerAMGSetStrongThreshold(s, 0.5); }},
      {"sys-agg1", [=](HYPRE_Solver s) { sys(s), HYPRE_BoomerAMGSetAggNumLevels(s, 1); }},
      {"sys-agg2", [=](HYPRE_Solver s) { sys(s), HYPRE_BoomerAMGSetAggNumLevels(s, 2); }},
      {"sys-agg1-pmis", [=](HYPRE_Solver s) {
         sys(s), HYPRE_BoomerAMGSetAggNumLevels(s, 1), HYPRE_BoomerAMGSetCoarsenType(s, 8);
       }},
      {"sys-agg1-st0.5", [=](HYPRE_Solver s) {
         sys(s), HYPRE_BoomerAMGSetAggNumLevels(s, 1), HYPRE_BoomerAMGSetStrongThreshold(s, 0.5);
       }},
      {"default-agg1", [](HYPRE_Solver s) { HYPRE_BoomerAMGSetAggNumLevels(s, 1); }},
      {"sys-agg1-cheb", [=](HYPRE_Solver s) {
         sys(s), HYPRE_BoomerAMGSetAggNumLevels(s, 1), HYPRE_BoomerAMGSetRelaxType(s, 16);
       }},
      {"nodal-frob", [=](HYPRE_Solver s) { sys(s), HYPRE_BoomerAMGSetNodal(s, 1); }},
      {"nodal-rowsum", [=](HYPRE_Solver s) { sys(s), HYPRE_BoomerAMGSetNodal(s, 4); }},
      {"nodal-frob-pmis", [=](HYPRE_Solver s) {
         sys(s), HYPRE_BoomerAMGSetNodal(s, 1), HYPRE_BoomerAMGSetCoarsenType(s, 8);
       }},
      {"nodal-frob-st0.5", [=](HYPRE_Solver s) {
         sys(s), HYPRE_BoomerAMGSetNodal(s, 1), HYPRE_BoomerAMGSetStrongThreshold(s, 0.5);
       }},
      {"nodal-frob-agg1", [=](HYPRE_Solver s) {
         sys(s), HYPRE_BoomerAMGSetNodal(s, 1), HYPRE_BoomerAMGSetAggNumLevels(s, 1);
       }},
      {"nodal-rbm", [=](HYPRE_Solver s) {
         sys(s), HYPRE_BoomerAMGSetNodal(s, 4), HYPRE_BoomerAMGSetInterpVecVariant(s, 2),
             HYPRE_BoomerAMGSetInterpVecQMax(s, 4);
       }, true},
      {"nodal-rbm-classical", [=](HYPRE_Solver s) {
         sys(s), HYPRE_BoomerAMGSetNodal(s, 4), HYPRE_BoomerAMGSetInterpVecVariant(s, 2),
             HYPRE_BoomerAMGSetInterpVecQMax(s, 4), HYPRE_BoomerAMGSetInterpType(s, 0);
       }, true},
  };
}

int run(int argc, char** argv) {
  CLI::App app{"Newton's linear solve: drape's multigrid against hypre's BoomerAMG on one drape state"};
  int n = 129, repeat = 1, max_it = 1000;
  double time = 0.12, dt = 5e-4, tol = 1e-6;
  std::string json, only;
  app.add_option("--size", n, "particles per side")->check(CLI::Range(9, 4001));
  app.add_option("--time", time, "simulated seconds before the solve")->check(CLI::Range(0.0, 10.0));
  app.add_option("--dt", dt, "fixed time step, s")->check(CLI::Range(1e-6, 1e-1));
  app.add_option("--tol", tol, "relative residual |b - K x| / |b| to reach")->check(CLI::Range(1e-14, 1.0));
  app.add_option("--max-iterations", max_it, "CG iterations at most")->check(CLI::Range(1, 100000));
  app.add_option("--repeat", repeat, "solves per method, the fastest reported")->check(CLI::Range(1, 100));
  app.add_option("--only", only, "BoomerAMG configurations whose name contains this");
  app.add_option("--json", json, "JSON file");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  int ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  if (ranks != 1) {
    std::fprintf(stderr, "hypre_compare: one rank only (the assembled K is one rank's)\n");
    return 2;
  }
  omp_set_num_threads(1);  // as hypre: the comparison is per core

  const Scene scene = landing_scene(n, dt);
  Simulation w(scene, load_fabric(scene.cloth.fabric));
  const double s0 = omp_get_wtime();
  step_to(w, time);
  const double stepping = omp_get_wtime() - s0;

  // The state's K and b, in the particle list's order (the compact order of
  // Newton's vectors; z's positions are 3 per grid particle).
  Evaluator& ev = w.loop->evaluator();
  double* z = w.cloth.z.data();
  ev.settled_cost(z);
  std::vector<double> diag(w.cloth.z.size()), v(w.cloth.z.size(), 0.0), kv(w.cloth.z.size());
  ev.stiffness_diagonal(z, diag.data());
  const std::vector<int64_t>& ids = w.lists.particles.items;
  for (int64_t p : ids)
    for (int k = 0; k < 3; ++k) v[3 * p + k] = 1e-3 * std::sin(double(3 * p + k));
  const double product = per_call([&] { ev.stiffness_product(z, v.data(), kv.data()); });
  BlockMatrix K;
  const double assemble = per_call([&] { ev.assemble_stiffness(K); });
  std::vector<double> b(3 * ids.size());
  const std::vector<double>& rho = ev.residual();
  for (size_t r = 0; r < ids.size(); ++r)
    for (int k = 0; k < 3; ++k) b[3 * r + k] = -rho[3 * r + k];  // the residual in list order
  std::vector<double> pos(3 * ids.size());
  double centroid[3] = {};
  for (size_t r = 0; r < ids.size(); ++r)
    for (int k = 0; k < 3; ++k) centroid[k] += z[3 * ids[r] + k] / double(ids.size());
  for (size_t r = 0; r < ids.size(); ++r)
    for (int k = 0; k < 3; ++k) pos[3 * r + k] = z[3 * ids[r] + k] - centroid[k];
  std::printf("size %d, t = %.4f s after %.1f s of stepping: %zu free particles, %lld blocks; "
              "stiffness product %.3f ms (CPU), K assembled %.2f products (not in the set-ups: both need it)\n",
              n, w.cloth.time, stepping, ids.size(), (long long)K.blocks(), 1e3 * product, assemble / product);
  std::fflush(stdout);

  HYPRE_Init();
  std::vector<Result> results;
  auto keep_best = [&](std::function<Result()> f) {
    Result best = f();
    for (int k = 1; k < repeat; ++k) {
      const Result r = f();
      best.setup = std::min(best.setup, r.setup);
      best.solve = std::min(best.solve, r.solve);
      best.wall = std::min(best.wall, r.wall);
    }
    results.push_back(best);
    const Result& r = results.back();
    std::printf("%-30s set-up %8.4f s (%7.1f products)  solve %8.4f s (%7.1f products)  iterations %4d  "
                "total %8.4f s (%7.1f products)  wall %8.4f s  |r|/|b| %.2e%s\n",
                r.name.c_str(), r.setup, r.setup / product, r.solve, r.solve / product, r.iterations, r.total(),
                r.total() / product, r.wall, r.residual, r.converged ? "" : "  NOT CONVERGED");
    std::fflush(stdout);
  };
  // The default settings (Newton's), then the smoother's other degrees: the
  // BoomerAMG rows are tuned too.
  for (int degree : {2, 1, 3}) {
    MultigridSettings ms;
    ms.degree = degree;
    const std::string name = degree == MultigridSettings{}.degree ? "multigrid" : "multigrid-d" + std::to_string(degree);
    keep_best([&] { return multigrid_solve(ms, name, K, ids, w.cloth.grid.ni, b, tol, max_it); });
  }
  for (const AmgConfig& c : configs())
    if (only.empty() || c.name.find(only) != std::string::npos)
      keep_best([&] { return boomeramg_solve(c, K, b, pos, tol, max_it); });
  HYPRE_Finalize();

  // Default against default, and the fastest (converged) of each family,
  // set-up included.
  auto fastest = [&](const std::string& family) {
    const Result* best = nullptr;
    for (const Result& r : results)
      if (r.name.rfind(family, 0) == 0 && r.converged && (!best || r.total() < best->total())) best = &r;
    return best;
  };
  auto compare = [&](const char* what, const Result* mg, const Result* amg) {
    if (!mg || !amg) return;
    std::printf("%s: %s %.4f s a solve, %s %.4f s: %s faster by %.2fx\n", what, mg->name.c_str(), mg->total(),
                amg->name.c_str(), amg->total(), amg->total() < mg->total() ? "BoomerAMG" : "multigrid",
                std::max(amg->total(), mg->total()) / std::min(amg->total(), mg->total()));
  };
  const Result* amg_default = nullptr;
  for (const Result& r : results)
    if (r.name == "boomeramg-default" && r.converged) amg_default = &r;
  compare("defaults", results.front().converged ? &results.front() : nullptr, amg_default);
  compare("fastest", fastest("multigrid"), fastest("boomeramg"));

  if (!json.empty()) {
    Json j;
    j.begin_object();
    j.value("size", n).value("time", w.cloth.time).value("dt", dt).value("tol", tol).value("repeat", repeat);
    j.value("free_particles", (long long)ids.size()).value("blocks", (long long)K.blocks());
    j.value("product_seconds", product).value("assemble_seconds", assemble);
    j.begin_array("methods");
    for (const Result& r : results) {
      j.begin_object();
      j.value("name", r.name).value("iterations", r.iterations).value("converged", r.converged);
      j.value("setup_seconds", r.setup).value("solve_seconds", r.solve).value("total_seconds", r.total());
      j.value("setup_products", r.setup / product).value("solve_products", r.solve / product);
      j.value("total_products", r.total() / product).value("relative_residual", r.residual);
      j.end_object();
    }
    j.end_array().end_object();
    std::ofstream(json) << j.str() << "\n";
  }
  return 0;
}

}  // namespace
}  // namespace drape

// A program start: hypre's IJ interface needs MPI, on one rank.
int main(int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  const int rc = drape::run(argc, argv);
  MPI_Finalize();
  return rc;
}
