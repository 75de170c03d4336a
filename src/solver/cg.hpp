#pragma once
// Nonlinear conjugate gradient (Polak-Ribiere+, diagonally scaled) with an
// Armijo line search and restarts: the minimizer of the paper's Algorithm 1.
// Dot products are summed per tile in a fixed order (docs/design.md §3).
#include <algorithm>
#include <cstdint>
#include <functional>
#include <type_traits>
#include <vector>

#include "solver/cost.hpp"
#include "solver/memory_table.hpp"
#include "solver/timers.hpp"

namespace drape {

struct CgSettings {
  int max_iterations = 200;
  double tolerance = 1e-6;   // on the cost per free particle
  int restart_every = 50;    // steepest-descent restart period
  bool numeric = false;      // finite-difference gradient (reference mode)
  int64_t free_particles = 1;  // global count, normalises the cost
  // Newton: the line search follows the step's energy slope (SlopeSearch)
  // instead of halving until the cost decreases.
  bool slope_search = false;
  // Newton: before the line search, a full step that lands elements on other
  // band branches is solved again from the same z with their secant
  // stiffness (BandActiveSet; the evaluator must track branches).
  bool active_set = false;
  // Newton: the linear solves' tolerance follows the residual's last
  // reduction (Eisenstat-Walker) instead of its size.
  bool adaptive_forcing = false;
  // Newton: the cost the evaluator settled at the starting z just before
  // (the time loop's guess): the first evaluation is not repeated.
  const CostTerms* settled_at_start = nullptr;
  // Asked once per iteration; true ends the minimisation (wall-clock budget,
  // signals). Must answer the same on every rank: the caller makes it collective.
  std::function<bool()> stop_requested;
};

struct CgResult {
  int iterations = 0;
  int evaluations = 0;
  int newton_iterations = 0;  // Newton steps (NewtonSolver; the CG leaves it 0)
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
  // f(k, acc) or f(c, k, acc): c numbers the unknowns below `end` in tile
  // order from 0 (compact vectors: consecutive in memory, however sparse the
  // mesh).
  template <int K, class F>
  void tile_sums(int64_t end, F&& f, double* out);
  // The same sums for f(c, acc), which reads compact vectors only: a tile's
  // numbers are consecutive, so its loop is one run however sparse the mesh.
  template <int K, class F>
  void compact_sums(int64_t end, F&& f, double* out);
  // f(c, k) for the same unknowns and numbering, in the same static chunks.
  template <class F>
  void for_each_unknown(int64_t end, F&& f);
  // How many unknowns lie below `end` (the compact vectors' length).
  int64_t unknowns_below(int64_t end) {
    number_unknowns(end);
    return tile_c_[lists_.tiles.size()];
  }
  // Its arrays' capacities.
  void memory(MemoryTable& t) const;
  const Reducer& reducer() const { return red_; }
  const Tiling& tiling() const { return tiling_; }
  // Gives its vectors back (a later minimize() sizes them again).
  void release();
  // After the lists changed: its vectors, where held, grow to the lists'
  // unknowns now (fit.hpp's rule), or with `exact` are sized to them.
  void fit_vectors(bool exact);

  // The nonlinear CG's order of this rank's unknowns (Evaluator's compact
  // order): each tile's sums run through it in the tile's z order, so
  // they are dot()'s over z, bit for bit. f(c, k): compact c, z index k.
  template <class F>
  void for_each_compact(F&& f);
  // K tile-ordered sums of f(c, acc) over that order.
  template <int K, class F>
  void block_sums(F&& f, double* out);

 private:
  // Each tile's first compact number (tile_c_), for the lists' stamp and `end`.
  void number_unknowns(int64_t end);
  template <class F>
  void tile_runs(int64_t end, F&& per_tile);

  CostTerms eval(Evaluator& ev, double* z, double* g, bool numeric);
  // The numeric gradient (reference mode) at z's indices, gathered into g.
  CostTerms numeric(Evaluator& ev, double* z, double* g);
  void size_vectors(bool numeric);
  double compact_dot(const double* a, const double* b) {
    double out;
    block_sums<1>([&](int64_t c, double* acc) { acc[0] += a[c] * b[c]; }, &out);
    return out;
  }
  // Where each block of the compact order starts (positions, tensions,
  // moments, shears) and ends (the last).
  void block_starts(int64_t b[5]) const;

  const Cloth& c_;
  const ActiveLists& lists_;
  const Tiling& tiling_;
  const Reducer& red_;
  // Compact: the gradient, the trial's, the scaled gradient, the direction,
  // the line search's start and the scaling diagonal.
  std::vector<double> g_, gn_, s_, d_, z0_, diag_, partials_;
  std::vector<double> numeric_;  // the numeric gradient at z's indices (reference mode only)
  std::vector<int64_t> tile_c_;  // tiles + 1
  uint64_t c_stamp_ = 0;
  int64_t c_end_ = -1;
  double alpha_ = 1.0;  // first trial step, carried from one iteration to the next
};

// per_tile(t, runs) for each owned tile, in static chunks; runs(run) calls
// run(lo, hi, c) for each of the tile's runs [lo, hi) below `end`, c being
// the compact number of lo.
template <class F>
void Minimizer::tile_runs(int64_t end, F&& per_tile) {
  number_unknowns(end);
  const IndexRuns& u = lists_.unknowns;
  const int64_t *tb = u.tile_begin.data(), *b = u.bounds.data(), *tc = tile_c_.data();
  const int nt = int(lists_.tiles.size());
  // Static: on a coarse mesh a tile holds a few unknowns, and handing out
  // hundreds of tiles one by one cost more than the products themselves.
  timed_region([&] {
#pragma omp for schedule(static) nowait
    for (int t = 0; t < nt; ++t)
      per_tile(t, [&](auto&& run) {
        int64_t c = tc[t];
        for (int64_t r = tb[t]; r < tb[t + 1] && b[2 * r] < end; ++r) {
          // The run's bounds in locals: read in the loop's test, they kept
          // GCC from vectorizing it (gathers, 10x slower at 257).
          const int64_t lo = b[2 * r], hi = std::min(end, b[2 * r + 1]);
          run(lo, hi, c);
          c += hi - lo;
        }
      });
  });
}

template <int K, class F>
void Minimizer::tile_sums(int64_t end, F&& f, double* out) {
  static_assert(K >= 1 && K <= 2, "partials_ holds two sums per tile (Minimizer's constructor)");
  const int nt = int(lists_.tiles.size());
  tile_runs(end, [&](int t, auto&& runs) {
    double acc[K] = {};
    runs([&](int64_t lo, int64_t hi, int64_t c) {
      if constexpr (std::is_invocable_v<F&, int64_t, int64_t, double*>)
        for (int64_t k = lo; k < hi; ++k) f(c + (k - lo), k, acc);
      else
        for (int64_t k = lo; k < hi; ++k) f(k, acc);
    });
    for (int j = 0; j < K; ++j) partials_[size_t(j) * nt + t] = acc[j];
  });
  red_.sum_tiles(lists_.tiles, partials_.data(), K, out);
}

template <int K, class F>
void Minimizer::compact_sums(int64_t end, F&& f, double* out) {
  static_assert(K >= 1 && K <= 2, "partials_ holds two sums per tile (Minimizer's constructor)");
  number_unknowns(end);
  const int64_t* tc = tile_c_.data();
  const int nt = int(lists_.tiles.size());
  timed_region([&] {
#pragma omp for schedule(static) nowait
    for (int t = 0; t < nt; ++t) {
      double acc[K] = {};
      const int64_t lo = tc[t], hi = tc[t + 1];
      for (int64_t c = lo; c < hi; ++c) f(c, acc);
      for (int j = 0; j < K; ++j) partials_[size_t(j) * nt + t] = acc[j];
    }
  });
  red_.sum_tiles(lists_.tiles, partials_.data(), K, out);
}

template <class F>
void Minimizer::for_each_compact(F&& f) {
  int64_t b[5];
  block_starts(b);
  const ActiveList* L[4] = {&lists_.particles, &lists_.edges, &lists_.triples, &lists_.shears};
  const Cloth& cl = c_;
  timed_region([&] {
    for (int k = 0; k < 4; ++k) {
      const int64_t* items = L[k]->items.data();
      const int64_t n = L[k]->size(), c0 = b[k];
      if (k == 0) {
#pragma omp for schedule(static) nowait
        for (int64_t r = 0; r < n; ++r)
          for (int j = 0; j < 3; ++j) f(3 * r + j, 3 * items[r] + j);
      } else {
#pragma omp for schedule(static) nowait
        for (int64_t r = 0; r < n; ++r) f(c0 + r, cl.force_index(k - 1, items[r]));
      }
    }
  });
}

template <int K, class F>
void Minimizer::block_sums(F&& f, double* out) {
  static_assert(K >= 1 && K <= 2, "partials_ holds two sums per tile (Minimizer's constructor)");
  int64_t b[5];
  block_starts(b);
  const ActiveList* L[4] = {&lists_.particles, &lists_.edges, &lists_.triples, &lists_.shears};
  const int nt = int(lists_.tiles.size());
  timed_region([&] {
#pragma omp for schedule(static) nowait
    for (int t = 0; t < nt; ++t) {
      double acc[K] = {};
      // The tile's positions, tensions, moments, shears: its runs' order in z.
      for (int k = 0; k < 4; ++k) {
        const int64_t w = k == 0 ? 3 : 1;
        const int64_t lo = b[k] + w * L[k]->tile_begin[t], hi = b[k] + w * L[k]->tile_begin[t + 1];
        for (int64_t c = lo; c < hi; ++c) f(c, acc);
      }
      for (int j = 0; j < K; ++j) partials_[size_t(j) * nt + t] = acc[j];
    }
  });
  red_.sum_tiles(lists_.tiles, partials_.data(), K, out);
}

template <class F>
void Minimizer::for_each_unknown(int64_t end, F&& f) {
  tile_runs(end, [&](int, auto&& runs) {
    runs([&](int64_t lo, int64_t hi, int64_t c) {
      for (int64_t k = lo; k < hi; ++k) f(c + (k - lo), k);
    });
  });
}

}  // namespace drape
