#pragma once
// Nonlinear conjugate gradient (Polak-Ribiere+, diagonally scaled) with an
// Armijo line search and restarts: the minimizer of the paper's Algorithm 1.
// Dot products are summed per tile in a fixed order (DESIGN §3).
#include <algorithm>
#include <cstdint>
#include <functional>
#include <vector>

#include "solver/cost.hpp"
#include "solver/timers.hpp"

namespace drape {

struct CgSettings {
  int max_iterations = 200;
  double tolerance = 1e-6;   // on the cost per free particle
  int restart_every = 50;    // steepest-descent restart period
  bool numeric = false;      // finite-difference gradient (reference mode)
  int64_t free_particles = 1;  // global count, normalises the cost
  // Asked once per iteration; true ends the minimisation (wall-clock budget,
  // signals). Must answer the same on every rank: the caller makes it collective.
  std::function<bool()> stop_requested;
};

struct CgResult {
  int iterations = 0;
  int evaluations = 0;
  bool converged = false;
  bool stalled = false;  // no descent possible (at machine precision)
  bool stopped = false;  // stop_requested() said so
  CostTerms cost;
  double cost_per_particle = 0;
};

class Minimizer {
 public:
  Minimizer(const Cloth& cloth, const ActiveLists& lists, const Tiling& tiling, const Reducer& red);

  // Minimizes from z in place. on_iteration(iteration, cost) after each step.
  CgResult minimize(Evaluator& ev, double* z, const CgSettings& s, Timers& timers,
                    const std::function<void(int, double)>& on_iteration = {});

  // The first trial step of the next line search: carried from iteration to
  // iteration and step to step, so a checkpoint keeps it.
  double first_step() const { return alpha_; }
  void set_first_step(double a) { alpha_ = a; }

  // Tile-ordered dot products (exposed for tests), over the unknowns below
  // `end` (a tile's runs come in z's block order: end = the tension block's
  // start keeps the positions).
  double dot(const double* a, const double* b, int64_t end = INT64_MAX);
  // K such sums in one pass: f(k, acc) adds unknown k's terms to acc[0..K),
  // and may update vectors element-wise on the way (one pass over memory and
  // one parallel region instead of one per vector). Same tile order as dot.
  template <int K, class F>
  void tile_sums(int64_t end, F&& f, double* out);

 private:
  CostTerms eval(Evaluator& ev, double* z, double* g, bool numeric);

  const Cloth& c_;
  const ActiveLists& lists_;
  const Tiling& tiling_;
  const Reducer& red_;
  std::vector<double> g_, gn_, s_, d_, zt_, diag_, partials_;
  double alpha_ = 1.0;  // first trial step, carried from one iteration to the next
};

template <int K, class F>
void Minimizer::tile_sums(int64_t end, F&& f, double* out) {
  static_assert(K >= 1 && K <= 2, "partials_ holds two sums per tile (Minimizer's constructor)");
  const IndexRuns& u = lists_.unknowns;
  const int64_t *tb = u.tile_begin.data(), *b = u.bounds.data();
  const int nt = int(lists_.tiles.size());
  // Static: on a coarse mesh a tile holds a few unknowns, and handing out
  // hundreds of tiles one by one cost more than the products themselves.
  timed_region([&] {
#pragma omp for schedule(static) nowait
    for (int t = 0; t < nt; ++t) {
      double acc[K] = {};
      for (int64_t r = tb[t]; r < tb[t + 1] && b[2 * r] < end; ++r) {
        // The run's bounds in locals: read in the loop's test, they kept GCC
        // from vectorizing it (gathers, 10x slower at 257).
        const int64_t lo = b[2 * r], hi = std::min(end, b[2 * r + 1]);
        for (int64_t k = lo; k < hi; ++k) f(k, acc);
      }
      for (int j = 0; j < K; ++j) partials_[size_t(j) * nt + t] = acc[j];
    }
  });
  red_.sum_tiles(lists_.tiles, partials_.data(), K, out);
}

}  // namespace drape
