// Time per gradient evaluation and per CG iteration at
// 1000 x 1000 on one rank, and the finite-difference / analytic gradient time
// ratio on 100 x 100, both gradients timed in the same run. The
// cost per active particle of an AMRC mesh against the finest mesh's (257),
// and what parts of a Newton step cost on either (one layout or pass
// against another, in the same run). BM_Kernels: each kernel's bytes
// (solver/traffic.hpp) over its seconds against a STREAM triad measured in
// the same run; --json FILE writes those figures (and the finite-difference
// ratio) to FILE.
//   build/bench/bench_gradient --benchmark_counters_tabular=true [--json FILE]
#include <benchmark/benchmark.h>
#include <omp.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "io/json.hpp"
#include "mid_drape.hpp"
#include "solver/traffic.hpp"

namespace drape {
namespace {

// A benchmark's world, built once per size (static in each benchmark).
struct Bed : Simulation {
  explicit Bed(int n, bool amrc = false) : Simulation(mid_drape_scene(n), load_fabric("denim-A")) {
    if (amrc) uneven_amrc_mesh(*this);
    jitter_mid_drape(*this, 42);
  }
  int64_t active() const {
    int64_t k = 0;
    for (uint8_t f : cloth.flags) k += (f & kActive) != 0;
    return k;
  }
};

// Figures for --json, by benchmark and name (filled as the benchmarks run).
std::map<std::string, std::map<std::string, double>>& results() {
  static std::map<std::string, std::map<std::string, double>> r;
  return r;
}

double seconds_of(const std::function<void()>& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// CPU seconds of the whole process (all threads): on a shared machine it
// leaves out the time other jobs held the cores.
double cpu_seconds_of(const std::function<void()>& f) {
  timespec a{}, b{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &a);
  f();
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &b);
  return double(b.tv_sec - a.tv_sec) + 1e-9 * double(b.tv_nsec - a.tv_nsec);
}

void BM_Gradient(benchmark::State& state) {
  static Bed bed(int(state.range(0)));
  std::vector<double> g(bed.cloth.z.size());
  for (auto _ : state) {
    const CostTerms c = bed.loop->evaluator().evaluate(bed.cloth.z.data(), g.data());
    benchmark::DoNotOptimize(c);
  }
  state.counters["particles"] = double(bed.cloth.grid.n());
  state.counters["threads"] = omp_get_max_threads();
}
// STREAM's triad a = b + s c over arrays far larger than the caches, on
// the threads the kernels use; the best of `reps` passes, in bytes / second
// counted as STREAM does (24 bytes an entry): by wall time, and by CPU time
// per thread (the kernels' CPU-time figures compare with this one).
struct Triad {
  double wall = 0, cpu = 0;
};
Triad triad_bandwidth(int reps = 8) {
  const int64_t n = int64_t(1) << 24;  // 3 x 128 MiB
  std::unique_ptr<double[]> a(new double[n]), b(new double[n]), c(new double[n]);
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i) a[i] = 0, b[i] = 1, c[i] = 2;  // first touch on the threads that use them
  double best = 1e30, best_cpu = 1e30;
  const double s = 3.0;
  for (int r = 0; r < reps; ++r) {
    double t = 0;
    const double cpu = cpu_seconds_of([&] {
      t = seconds_of([&] {
        double *pa = a.get(), *pb = b.get(), *pc = c.get();
#pragma omp parallel for schedule(static)
        for (int64_t i = 0; i < n; ++i) pa[i] = pb[i] + s * pc[i];
      });
    });
    best = std::min(best, t);
    best_cpu = std::min(best_cpu, cpu / omp_get_max_threads());
  }
  benchmark::DoNotOptimize(a.get());
  return {24.0 * double(n) / best, 24.0 * double(n) / best_cpu};
}

// Each kernel at n x n on the given threads: the best of its repetitions'
// seconds, the bytes the model says it moves, their ratio, and that
// bandwidth's share of a triad measured in the same run (before and after
// the kernels, the better of the two).
void BM_Kernels(benchmark::State& state) {
  static Bed bed(int(state.range(0)));
  Evaluator& ev = bed.loop->evaluator();
  double* z = bed.cloth.z.data();
  const size_t nz = bed.cloth.z.size();
  std::vector<double> g(nz), v(nz, 1e-6), kv(nz), diag(nz);
  ev.evaluate(z, g.data());  // lists and rows set up outside the timing
  ev.settled_cost(z);
  ev.stiffness_diagonal_local(z, diag.data());
  const TrafficCounts counts = traffic_counts(ev.lists(), bed.cloth);
  struct Kernel {
    const char* name;
    KernelBytes bytes;
    std::function<void()> run;
    double best = 1e30, best_cpu = 1e30;
  };
  // The product first: evaluate() ends the settled numbers it reads (they
  // stay kept: kg_ready_), not its kept ones.
  Kernel kernels[] = {
      {"stiffness_product", product_bytes(), [&] { ev.stiffness_product_local(z, v.data(), kv.data()); }},
      {"cost", cost_bytes(), [&] { ev.evaluate(z, nullptr); }},
      {"cost_gradient", cost_gradient_bytes(), [&] { ev.evaluate(z, g.data()); }},
  };
  const Triad t0 = triad_bandwidth();
  double triad = t0.wall, triad_cpu = t0.cpu;
  for (auto _ : state)
    for (Kernel& k : kernels) {
      double wall = 0;
      const double cpu = cpu_seconds_of([&] { wall = seconds_of(k.run); });
      k.best = std::min(k.best, wall);
      k.best_cpu = std::min(k.best_cpu, cpu);
    }
  const Triad t1 = triad_bandwidth();
  triad = std::max(triad, t1.wall);
  triad_cpu = std::max(triad_cpu, t1.cpu);
  auto& out = results()["kernels"];
  out["n"] = double(state.range(0));
  out["particles"] = double(counts.particles);
  out["threads"] = omp_get_max_threads();
  out["triad_GBps"] = 1e-9 * triad;
  out["triad_cpu_GBps"] = 1e-9 * triad_cpu;
  state.counters["triad_GBps"] = 1e-9 * triad;
  // A nonlinear CG iteration evaluates the cost and gradient at least once:
  // 100 of them move at least 100 times its bytes, at the triad's rate at best.
  out["cg100_memory_bound_s"] = 100 * cost_gradient_bytes().total(counts) / triad;
  state.counters["cg100_bound_s"] = out["cg100_memory_bound_s"];
  for (const Kernel& k : kernels) {
    const double bytes = k.bytes.total(counts), gbps = 1e-9 * bytes / k.best;
    const std::string n = k.name;
    out[n + "_s"] = k.best;
    out[n + "_bytes"] = bytes;
    out[n + "_bytes_per_particle"] = bytes / double(counts.particles);
    out[n + "_GBps"] = gbps;
    out[n + "_of_triad"] = gbps / (1e-9 * triad);
    // The same from CPU time per thread, against the triad's: on a loaded
    // machine, each one's own time without the waits for a core (a thread's
    // spin at a barrier still counts).
    const double cpu_per_thread = k.best_cpu / omp_get_max_threads();
    out[n + "_cpu_s"] = k.best_cpu;
    out[n + "_of_triad_cpu"] = bytes / cpu_per_thread / triad_cpu;
    state.counters[n + "_ms"] = 1e3 * k.best;
    state.counters[n + "_of_triad"] = gbps / (1e-9 * triad);
    state.counters[n + "_of_triad_cpu"] = out[n + "_of_triad_cpu"];
  }
}
BENCHMARK(BM_Kernels)->Arg(1000)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);

BENCHMARK(BM_Gradient)->Arg(1000)->Unit(benchmark::kMillisecond)->UseRealTime();

// Cost + gradient in one parallel region against the separate regions
// (Evaluator::fuse_gradient; the same numbers), back to back in each
// repetition, each the best of its repetitions by wall and by CPU time.
void BM_FusedOverApart(benchmark::State& state) {
  const int n = int(state.range(0));
  static std::map<int, std::unique_ptr<Bed>> made;
  if (!made.count(n)) made[n] = std::make_unique<Bed>(n);
  Bed& bed = *made[n];
  Evaluator& ev = bed.loop->evaluator();
  std::vector<double> g(bed.cloth.z.size());
  double wall[2] = {1e30, 1e30}, cpu[2] = {1e30, 1e30};
  const int per = n <= 200 ? 20 : 1;
  for (auto _ : state)
    for (int fused : {1, 0}) {
      ev.fuse_gradient(fused);
      for (int k = 0; k < per; ++k) {
        double w = 0;
        const double c = cpu_seconds_of([&] { w = seconds_of([&] { ev.evaluate(bed.cloth.z.data(), g.data()); }); });
        wall[fused] = std::min(wall[fused], w);
        cpu[fused] = std::min(cpu[fused], c);
      }
    }
  ev.fuse_gradient(true);
  state.counters["fused_ms"] = 1e3 * wall[1];
  state.counters["apart_ms"] = 1e3 * wall[0];
  state.counters["fused_over_apart"] = wall[1] / wall[0];
  state.counters["cpu_fused_over_apart"] = cpu[1] / cpu[0];
  state.counters["threads"] = omp_get_max_threads();
}
BENCHMARK(BM_FusedOverApart)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);

// The Newton solver's inner iteration: one stiffness product K v.
void BM_StiffnessProduct(benchmark::State& state) {
  static Bed bed(int(state.range(0)));
  // z's size: room for the own numbering's 3 a particle (the product's vectors).
  std::vector<double> v(bed.cloth.z.size(), 1e-6), kv(bed.cloth.z.size()), diag(bed.cloth.z.size());
  bed.loop->evaluator().hysteresis_forces(bed.cloth.z.data());
  bed.loop->evaluator().stiffness_diagonal_local(bed.cloth.z.data(), diag.data());  // freezes the band slopes
  // The diagonal keeps the z-only numbers; the products, which this times,
  // read them (one Newton linear solve: a diagonal, then dozens).
  bed.loop->evaluator().stiffness_product_local(bed.cloth.z.data(), v.data(), kv.data());
  for (auto _ : state) {
    bed.loop->evaluator().stiffness_product_local(bed.cloth.z.data(), v.data(), kv.data());
    benchmark::DoNotOptimize(kv.data());
  }
}
BENCHMARK(BM_StiffnessProduct)->Arg(1000)->Unit(benchmark::kMillisecond)->UseRealTime();

// One Newton linear solve's worth of products (a diagonal, then 20
// products at one z), with the products' z-only numbers kept and computed
// anew, back to back in every repetition: where keeping them pays.
void BM_KeptProducts(benchmark::State& state) {
  Bed bed(int(state.range(0)));
  Evaluator& ev = bed.loop->evaluator();
  std::vector<double> v(bed.cloth.z.size(), 1e-6), kv(bed.cloth.z.size()), diag(bed.cloth.z.size());
  ev.hysteresis_forces(bed.cloth.z.data());
  const int per = 20;
  double seconds[2] = {};
  for (auto _ : state)
    for (int keep = 0; keep < 2; ++keep) {
      state.PauseTiming();
      ev.keep_products(keep == 1);
      state.ResumeTiming();
      seconds[keep] += cpu_seconds_of([&] {
        ev.stiffness_diagonal_local(bed.cloth.z.data(), diag.data());
        for (int k = 0; k < per; ++k) ev.stiffness_product_local(bed.cloth.z.data(), v.data(), kv.data());
      });
    }
  const double n = double(state.iterations()) * per;
  state.counters["computed_ms"] = 1e3 * seconds[0] / n;
  state.counters["kept_ms"] = 1e3 * seconds[1] / n;
  state.counters["kept_over_computed"] = seconds[1] / seconds[0];
}
BENCHMARK(BM_KeptProducts)->Arg(257)->Arg(513)->Arg(1000)->Unit(benchmark::kMillisecond)->UseRealTime()
    ->Iterations(3);

void BM_CgIteration(benchmark::State& state) {
  static Bed bed(int(state.range(0)));
  const int per = 10;
  CgSettings cs;
  cs.max_iterations = per;
  cs.tolerance = 0;  // never converged: exactly `per` iterations unless stalled
  cs.free_particles = bed.loop->free_particles();
  Timers tm;
  int iterations = 0, evaluations = 0;
  const uint64_t builds0 = bed.loop->evaluator().self_contact().builds();
  for (auto _ : state) {
    const CgResult r = bed.loop->minimizer().minimize(bed.loop->evaluator(), bed.cloth.z.data(), cs, tm);
    iterations += r.iterations;
    evaluations += r.evaluations;
  }
  state.counters["iterations"] = iterations;
  state.counters["evaluations"] = evaluations;
  // The self-contact pair list's builds over the iterations.
  state.counters["pair_builds"] = double(bed.loop->evaluator().self_contact().builds() - builds0);
  state.counters["s_per_iteration"] =
      benchmark::Counter(iterations, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_CgIteration)->Arg(1000)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(2);

// AMRC's price per active particle against the finest mesh's, on one grid:
// a stiffness product and a cost + gradient on each mesh, back to back in
// every repetition, in CPU time. A coarse mesh's particles (and their elements' slots) lie
// apart in memory, so each costs more than a finest-mesh particle; the ratio
// is what AMRC's speed-up loses to that, beside its share of particles.
void BM_AmrcPerParticle(benchmark::State& state) {
  const int n = int(state.range(0));
  // Built once per size (the benchmark calls this more than once); in place:
  // a Simulation's parts refer to one another.
  static std::map<int, std::unique_ptr<Bed>[2]> made;
  if (!made.count(n)) made[n][0] = std::make_unique<Bed>(n), made[n][1] = std::make_unique<Bed>(n, true);
  Bed &fine = *made[n][0], &coarse = *made[n][1];
  Bed* beds[2] = {&fine, &coarse};
  std::vector<double> v[2], kv[2], g[2];
  for (int b = 0; b < 2; ++b) {
    const size_t size = beds[b]->cloth.z.size();
    v[b].assign(size, 1e-6), kv[b].assign(size, 0.0), g[b].assign(size, 0.0);
    std::vector<double> diag(size);
    beds[b]->loop->evaluator().hysteresis_forces(beds[b]->cloth.z.data());
    beds[b]->loop->evaluator().stiffness_diagonal_local(beds[b]->cloth.z.data(), diag.data());
  }
  double product[2] = {}, gradient[2] = {};
  const int per = 5;
  for (auto _ : state)
    for (int b = 0; b < 2; ++b) {
      Evaluator& ev = beds[b]->loop->evaluator();
      double* z = beds[b]->cloth.z.data();
      product[b] += cpu_seconds_of([&] {
        for (int k = 0; k < per; ++k) ev.stiffness_product_local(z, v[b].data(), kv[b].data());
      });
      gradient[b] += cpu_seconds_of([&] {
        for (int k = 0; k < per; ++k) ev.evaluate(z, g[b].data());
      });
    }
  const double reps = double(state.iterations()) * per;
  const double ns[4] = {1e9 * product[0] / reps / fine.active(), 1e9 * product[1] / reps / coarse.active(),
                        1e9 * gradient[0] / reps / fine.active(), 1e9 * gradient[1] / reps / coarse.active()};
  state.counters["share"] = double(coarse.active()) / fine.active();
  state.counters["product_ns_fine"] = ns[0];
  state.counters["product_ns_amrc"] = ns[1];
  state.counters["product_amrc_over_fine"] = ns[1] / ns[0];
  state.counters["gradient_ns_fine"] = ns[2];
  state.counters["gradient_ns_amrc"] = ns[3];
  state.counters["gradient_amrc_over_fine"] = ns[3] / ns[2];
}
BENCHMARK(BM_AmrcPerParticle)->Arg(129)->Arg(257)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

// A Newton step's work outside its linear CG iterations: a line search
// trial (forces set to their hysteresis targets, the cost), then K's diagonal
// and the linear solve's first product at the accepted z. Timed both ways
// back to back in each repetition, on the finest and an AMRC mesh: the
// separate passes (hysteresis_forces, evaluate, and a diagonal that
// computes the elements' geometry again) and settled_cost, whose numbers
// the diagonal and product read. The same numbers, bit for bit
// (tests: Stiffness.SettledCostIsHysteresisForcesThenEvaluate).
void BM_NewtonStepOverhead(benchmark::State& state) {
  const int n = int(state.range(0));
  static std::map<int, std::unique_ptr<Bed>[2]> made;
  if (!made.count(n)) made[n][0] = std::make_unique<Bed>(n), made[n][1] = std::make_unique<Bed>(n, true);
  Bed* beds[2] = {made[n][0].get(), made[n][1].get()};
  double seconds[2][2] = {};  // [mesh][settled]
  for (auto _ : state)
    for (int b = 0; b < 2; ++b)
      for (int settled = 0; settled < 2; ++settled) {
        Evaluator& ev = beds[b]->loop->evaluator();
        double* z = beds[b]->cloth.z.data();
        const size_t size = beds[b]->cloth.z.size();
        state.PauseTiming();
        std::vector<double> v(size, 1e-6), kv(size), diag(size);
        state.ResumeTiming();
        seconds[b][settled] += cpu_seconds_of([&] {
          if (settled) {
            ev.settled_cost(z);
          } else {
            ev.hysteresis_forces(z);
            ev.evaluate(z, nullptr);
          }
          ev.stiffness_diagonal_local(z, diag.data());
          ev.stiffness_product_local(z, v.data(), kv.data());
        });
      }
  const double reps = double(state.iterations());
  state.counters["share"] = double(beds[1]->active()) / beds[0]->active();
  state.counters["fine_separate_ms"] = 1e3 * seconds[0][0] / reps;
  state.counters["fine_settled_over_separate"] = seconds[0][1] / seconds[0][0];
  state.counters["amrc_separate_ms"] = 1e3 * seconds[1][0] / reps;
  state.counters["amrc_settled_over_separate"] = seconds[1][1] / seconds[1][0];
}
BENCHMARK(BM_NewtonStepOverhead)->Arg(257)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

// One linear-CG iteration's vector passes (NewtonSolver::linear_solve: p.Kp,
// the fused step / residual pass, the direction update) per unknown, on the
// finest and an AMRC mesh, with the vectors compact (the solver's layout:
// unknowns numbered in tile order) and at z's indices (its earlier layout), back to back in each repetition over the same lists.
void BM_LinearSolveVectors(benchmark::State& state) {
  const int n = int(state.range(0));
  static std::map<int, std::unique_ptr<Bed>[2]> made;
  if (!made.count(n)) made[n][0] = std::make_unique<Bed>(n), made[n][1] = std::make_unique<Bed>(n, true);
  Bed* beds[2] = {made[n][0].get(), made[n][1].get()};
  double seconds[2][2] = {}, unknowns[2] = {};  // [mesh][compact]
  const int per = 20;
  for (auto _ : state)
    for (int b = 0; b < 2; ++b) {
      Minimizer& m = beds[b]->loop->minimizer();
      const int64_t end = beds[b]->cloth.layout.tension();
      const size_t nz = beds[b]->cloth.z.size(), nc = size_t(m.unknowns_below(end));
      unknowns[b] = double(nc);
      state.PauseTiming();
      std::vector<double> g[6], c[6];  // d, r, s, p, Kp, diag
      for (int k = 0; k < 6; ++k) g[k].assign(nz, k == 5 ? 2.0 : 1e-3), c[k].assign(nc, k == 5 ? 2.0 : 1e-3);
      state.ResumeTiming();
      double *d = g[0].data(), *r = g[1].data(), *s = g[2].data(), *p = g[3].data(), *kp = g[4].data(),
             *diag = g[5].data();
      double *dn = c[0].data(), *rn = c[1].data(), *sn = c[2].data(), *pn = c[3].data(), *kpn = c[4].data(),
             *diagn = c[5].data();
      double pg_sum = 0, sums[2];
      const double a = 1e-9, beta = 0.5;
      seconds[b][0] += cpu_seconds_of([&] {
        for (int it = 0; it < per; ++it) {
          m.tile_sums<1>(end, [&](int64_t k, double* acc) { acc[0] += p[k] * kp[k]; }, &pg_sum);
          m.tile_sums<2>(end, [&](int64_t k, double* acc) {
            d[k] += a * p[k];
            r[k] -= a * kp[k];
            s[k] = r[k] / diag[k];
            acc[0] += r[k] * r[k];
            acc[1] += r[k] * s[k];
          }, sums);
          m.for_each_unknown(end, [&](int64_t, int64_t k) { p[k] = s[k] + beta * p[k]; });
        }
      });
      seconds[b][1] += cpu_seconds_of([&] {
        for (int it = 0; it < per; ++it) {
          m.tile_sums<1>(end, [&](int64_t i, int64_t k, double* acc) {
            kpn[i] = kp[k];
            acc[0] += pn[i] * kpn[i];
          }, &pg_sum);
          m.compact_sums<2>(end, [&](int64_t i, double* acc) {
            dn[i] += a * pn[i];
            rn[i] -= a * kpn[i];
            sn[i] = rn[i] / diagn[i];
            acc[0] += rn[i] * rn[i];
            acc[1] += rn[i] * sn[i];
          }, sums);
          m.for_each_unknown(end, [&](int64_t i, int64_t k) {
            pn[i] = sn[i] + beta * pn[i];
            p[k] = pn[i];
          });
        }
      });
      benchmark::DoNotOptimize(sums);
    }
  const double reps = double(state.iterations()) * per;
  state.counters["share"] = unknowns[1] / unknowns[0];
  for (int b = 0; b < 2; ++b) {
    const char* mesh = b ? "amrc" : "fine";
    state.counters[std::string(mesh) + "_grid_ns"] = 1e9 * seconds[b][0] / reps / unknowns[b];
    state.counters[std::string(mesh) + "_compact_over_grid"] = seconds[b][1] / seconds[b][0];
  }
}
BENCHMARK(BM_LinearSolveVectors)->Arg(257)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

// Both gradients timed back to back in each repetition: the ratio is a
// measurement of one run, not of two runs on a shared machine. Each the
// best of its repetitions (the analytic one, milliseconds, of ten a
// repetition): on cores shared with other jobs the mean measured them.
void BM_NumericOverAnalytic(benchmark::State& state) {
  static Bed bed(int(state.range(0)));
  std::vector<double> g(bed.cloth.z.size());
  // Wall and CPU time, each the best: on a loaded machine a descheduled
  // thread can stretch a millisecond evaluation's wall time a hundredfold.
  double analytic = 1e30, numeric = 1e30, analytic_cpu = 1e30, numeric_cpu = 1e30;
  Evaluator& ev = bed.loop->evaluator();
  for (auto _ : state) {
    for (int k = 0; k < 10; ++k) {
      analytic = std::min(analytic, seconds_of([&] { ev.evaluate(bed.cloth.z.data(), g.data()); }));
      analytic_cpu = std::min(analytic_cpu, cpu_seconds_of([&] { ev.evaluate(bed.cloth.z.data(), g.data()); }));
    }
    numeric = std::min(numeric, seconds_of([&] { ev.numeric_gradient(bed.cloth.z.data(), g.data()); }));
    numeric_cpu = std::min(numeric_cpu, cpu_seconds_of([&] { ev.numeric_gradient(bed.cloth.z.data(), g.data()); }));
  }
  state.counters["analytic_ms"] = 1e3 * analytic;
  state.counters["numeric_ms"] = 1e3 * numeric;
  state.counters["numeric_over_analytic"] = numeric / analytic;
  state.counters["cpu_numeric_over_analytic"] = numeric_cpu / analytic_cpu;
  auto& out = results()["numeric_over_analytic"];
  out["n"] = double(state.range(0));
  out["analytic_s"] = analytic;
  out["numeric_s"] = numeric;
  out["ratio"] = numeric / analytic;
  out["analytic_cpu_s"] = analytic_cpu;
  out["numeric_cpu_s"] = numeric_cpu;
  out["cpu_ratio"] = numeric_cpu / analytic_cpu;
}
BENCHMARK(BM_NumericOverAnalytic)->Arg(100)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

}  // namespace
}  // namespace drape

// Google Benchmark's main, with --json FILE taken out of the arguments first.
int main(int argc, char** argv) {
  std::string json;
  int kept = 1;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--json") == 0) {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench_gradient: --json needs a file name\n");
        return 2;
      }
      json = argv[++i];
    } else {
      argv[kept++] = argv[i];
    }
  }
  argc = kept;
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  if (json.empty()) return 0;
  drape::Json j;
  j.begin_object();
  for (const auto& [bench, figures] : drape::results()) {
    j.begin_object(bench.c_str());
    for (const auto& [name, value] : figures) j.value(name.c_str(), value);
    j.end_object();
  }
  j.end_object();
  std::FILE* f = std::fopen(json.c_str(), "w");
  if (!f || std::fputs((j.str() + "\n").c_str(), f) < 0 || std::fclose(f) != 0) {
    std::fprintf(stderr, "bench_gradient: cannot write %s\n", json.c_str());
    return 1;
  }
  return 0;
}
