// Issue 2's figures: time per gradient evaluation and per CG iteration at
// 1000 x 1000 on one rank, and the finite-difference / analytic gradient time
// ratio on 100 x 100, both gradients timed in the same run.
//   build/bench/bench_gradient --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>
#include <omp.h>

#include <chrono>
#include <functional>

#include "mid_drape.hpp"

namespace drape {
namespace {

// A benchmark's world, built once per size (static in each benchmark).
struct Bed : World {
  explicit Bed(int n) : World(mid_drape_scene(n), load_fabric("denim-A")) { jitter_mid_drape(*this, 42); }
};

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
BENCHMARK(BM_Gradient)->Arg(1000)->Unit(benchmark::kMillisecond)->UseRealTime();

// The Newton solver's inner iteration: one stiffness product K v.
void BM_StiffnessProduct(benchmark::State& state) {
  static Bed bed(int(state.range(0)));
  std::vector<double> v(bed.cloth.z.size(), 1e-6), kv(bed.cloth.z.size()), diag(bed.cloth.z.size());
  bed.loop->evaluator().hysteresis_forces(bed.cloth.z.data());
  bed.loop->evaluator().stiffness_diagonal(bed.cloth.z.data(), diag.data());  // freezes the band slopes
  for (auto _ : state) {
    bed.loop->evaluator().stiffness_product(bed.cloth.z.data(), v.data(), kv.data());
    benchmark::DoNotOptimize(kv.data());
  }
}
BENCHMARK(BM_StiffnessProduct)->Arg(1000)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_CgIteration(benchmark::State& state) {
  static Bed bed(int(state.range(0)));
  const int per = 10;
  CgSettings cs;
  cs.max_iterations = per;
  cs.tolerance = 0;  // never converged: exactly `per` iterations unless stalled
  cs.free_particles = bed.loop->free_particles();
  Timers tm;
  int iterations = 0;
  for (auto _ : state) {
    const CgResult r = bed.loop->minimizer().minimize(bed.loop->evaluator(), bed.cloth.z.data(), cs, tm);
    iterations += r.iterations;
  }
  state.counters["iterations"] = iterations;
  state.counters["s_per_iteration"] =
      benchmark::Counter(iterations, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_CgIteration)->Arg(1000)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(2);

double seconds_of(const std::function<void()>& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Both gradients timed back to back in each repetition: the ratio is a
// measurement of one run, not of two runs on a shared machine.
void BM_NumericOverAnalytic(benchmark::State& state) {
  static Bed bed(int(state.range(0)));
  std::vector<double> g(bed.cloth.z.size());
  double analytic = 0, numeric = 0;
  for (auto _ : state) {
    analytic += seconds_of([&] { bed.loop->evaluator().evaluate(bed.cloth.z.data(), g.data()); });
    numeric += seconds_of([&] { bed.loop->evaluator().numeric_gradient(bed.cloth.z.data(), g.data()); });
  }
  state.counters["analytic_ms"] = 1e3 * analytic / state.iterations();
  state.counters["numeric_ms"] = 1e3 * numeric / state.iterations();
  state.counters["numeric_over_analytic"] = numeric / analytic;
}
BENCHMARK(BM_NumericOverAnalytic)->Arg(100)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

}  // namespace
}  // namespace drape

BENCHMARK_MAIN();
