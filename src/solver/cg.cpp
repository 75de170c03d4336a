#include "solver/cg.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "solver/fit.hpp"

namespace drape {

Minimizer::Minimizer(const Cloth& cloth, const ActiveLists& lists, const Tiling& tiling,
                     const Reducer& red)
    : c_(cloth), lists_(lists), tiling_(tiling), red_(red) {
  partials_.assign(2 * size_t(tiling.count()), 0.0);  // up to 2 sums at once
  tile_c_.assign(size_t(tiling.count()) + 1, 0);
}

// Sized at the first minimize(), not with the time loop: Newton's runs use
// this class for its tile-ordered sums only, and would hold them for nothing.
// Compact: this rank's unknowns only (Evaluator::compact_size), whatever the
// grid's size; the numeric gradient alone (one rank, reference mode) takes
// one vector at z's indices.
void Minimizer::size_vectors(bool numeric) {
  int64_t b[5];
  block_starts(b);
  const size_t n = size_t(b[4]), most = c_.layout.size();
  for (auto* v : {&g_, &gn_, &s_, &d_, &z0_, &diag_}) fit(*v, n, most, false, 0.0);
  if (numeric && numeric_.size() != most) numeric_.assign(most, 0.0);
}

void Minimizer::fit_vectors(bool exact) {
  if (g_.capacity() == 0) return;  // not held: the next minimize() sizes them
  int64_t b[5];
  block_starts(b);
  for (auto* v : {&g_, &gn_, &s_, &d_, &z0_, &diag_}) fit(*v, size_t(b[4]), c_.layout.size(), exact, 0.0);
}

void Minimizer::release() {
  for (auto* v : {&g_, &gn_, &s_, &d_, &z0_, &diag_, &numeric_}) std::vector<double>().swap(*v);
}

void Minimizer::memory(MemoryTable& t) const {
  t.add("Minimizer", "g, g new, s, d, z0, diagonal (nonlinear CG, compact)",
        (g_.capacity() + gn_.capacity() + s_.capacity() + d_.capacity() + z0_.capacity() + diag_.capacity()) * 8);
  t.add("Minimizer", "numeric gradient at z's indices (reference mode)", numeric_);
}

void Minimizer::block_starts(int64_t b[5]) const {
  b[0] = 0;
  b[1] = 3 * lists_.particles.size();
  b[2] = b[1] + lists_.edges.size();
  b[3] = b[2] + lists_.triples.size();
  b[4] = b[3] + lists_.shears.size();
}

void Minimizer::number_unknowns(int64_t end) {
  if (c_stamp_ == lists_.stamp && c_end_ == end && lists_.stamp != 0) return;
  const IndexRuns& u = lists_.unknowns;
  const size_t nt = lists_.tiles.size();
  int64_t c = 0;
  for (size_t t = 0; t < nt; ++t) {
    tile_c_[t] = c;
    for (int64_t r = u.tile_begin[t]; r < u.tile_begin[t + 1] && u.bounds[2 * r] < end; ++r)
      c += std::min(end, u.bounds[2 * r + 1]) - u.bounds[2 * r];
  }
  tile_c_[nt] = c;
  c_stamp_ = lists_.stamp;
  c_end_ = end;
}

double Minimizer::dot(const double* a, const double* b, int64_t end) {
  double out;
  tile_sums<1>(end, [&](int64_t k, double* acc) { acc[0] += a[k] * b[k]; }, &out);
  return out;
}

CostTerms Minimizer::numeric(Evaluator& ev, double* z, double* g) {
  const CostTerms c = ev.numeric_gradient(z, numeric_.data());
  const double* ng = numeric_.data();
  for_each_compact([&](int64_t c, int64_t k) { g[c] = ng[k]; });
  return c;
}

CostTerms Minimizer::eval(Evaluator& ev, double* z, double* g, bool numeric_mode) {
  return numeric_mode ? numeric(ev, z, g) : ev.evaluate_compact(z, g);
}

namespace {
bool finite(const CostTerms& c) { return std::isfinite(c.total()); }
}  // namespace

// The vectors are compact (block_sums' order); the trials are written into
// z's unknowns in place, from their compact copy z0 taken where the line
// search starts.
CgResult Minimizer::minimize(Evaluator& ev, double* z, const CgSettings& st, Timers& tm,
                             const std::function<void(int, double)>& on_iteration) {
  const double norm = 1.0 / double(std::max<int64_t>(1, st.free_particles));
  size_vectors(st.numeric);
  const int64_t n = int64_t(g_.size());
  double* g = g_.data();
  double* gn = gn_.data();
  double* s = s_.data();
  double* d = d_.data();
  double* z0 = z0_.data();
  const double* diag = diag_.data();
  CgResult res;
  {
    ScopedPhase ph(tm, kScaling);
    ev.scaling_diagonal_compact(z, diag_.data());
  }
  {
    ScopedPhase ph(tm, kGradient);
    res.cost = eval(ev, z, g, st.numeric);
  }
  res.evaluations = 1;
  double c0 = res.cost.total();
  if (!std::isfinite(c0)) return res;  // the caller reports where
  double gs;
  {
    ScopedPhase ph(tm, kVector);
    parallel_for(n, [&](int64_t c) {
      s[c] = g[c] / diag[c];
      d[c] = -s[c];
    });
    gs = compact_dot(g, s);
    for_each_compact([&](int64_t c, int64_t k) { z0[c] = z[k]; });
  }
  int since_restart = 0;
  bool steepest = true;
  while (res.iterations < st.max_iterations) {
    if (c0 * norm < st.tolerance) {
      res.converged = true;
      break;
    }
    if (st.stop_requested && st.stop_requested()) {
      res.stopped = true;
      break;
    }
    double gd = compact_dot(g, d);
    if (!(gd < 0)) {  // not a descent direction: restart
      parallel_for(n, [&](int64_t c) { d[c] = -s[c]; });
      gd = -gs;
      steepest = true;
    }
    if (!(gd < 0)) {  // zero gradient
      res.converged = c0 * norm < st.tolerance;
      res.stalled = !res.converged;
      break;
    }
    // Armijo backtracking with quadratic interpolation.
    double a = alpha_, ct = 0, dn = 0;
    bool ok = false;
    for (int tries = 0; tries < 30; ++tries) {
      {
        ScopedPhase ph(tm, kVector);
        for_each_compact([&](int64_t c, int64_t k) { z[k] = z0[c] + a * d[c]; });
      }
      CostTerms trial;
      {
        // A trial's cost only: its gradient waits until it is accepted.
        ScopedPhase ph(tm, tries == 0 ? kGradient : kLineSearch);
        trial = st.numeric ? numeric(ev, z, gn) : ev.cost_for_gradient(z);
      }
      ++res.evaluations;
      ct = trial.total();
      if (finite(trial) && ct <= c0 + 1e-4 * a * gd && ct < c0) {
        res.cost = trial;
        ok = true;
        break;
      }
      // Minimiser of the parabola through c0, gd and ct, kept within [a/10, a/2].
      double an = std::isfinite(ct) ? -gd * a * a / (2.0 * (ct - c0 - gd * a)) : 0.1 * a;
      if (!(an > 0.1 * a)) an = 0.1 * a;
      a = std::min(an, 0.5 * a);
    }
    if (!ok) {
      // Back to where the line search began (its hanging particles too).
      for_each_compact([&](int64_t c, int64_t k) { z[k] = z0[c]; });
      ev.interpolate_hanging(z);
      if (steepest) {
        res.stalled = true;
        break;
      }
      // Retry along steepest descent once.
      parallel_for(n, [&](int64_t c) { d[c] = -s[c]; });
      steepest = true;
      alpha_ = 1.0;
      continue;
    }
    if (!st.numeric) {
      ScopedPhase ph(tm, kGradient);
      ev.gradient_at_last_cost_compact(gn);  // at z, from its cost pass's numbers
    }
    ScopedPhase ph(tm, kVector);
    dn = compact_dot(gn, d);
    // Next first trial: the secant estimate of the line minimum.
    const double sec = (dn - gd) > 0 ? a * (-gd) / (dn - gd) : 4.0 * a;
    alpha_ = std::clamp(sec, 0.1 * a, 10.0 * a);
    for_each_compact([&](int64_t c, int64_t k) { z0[c] = z[k]; });
    std::swap(g, gn);
    const double gs_old = gs;
    const double g_sold = compact_dot(g, s);
    parallel_for(n, [&](int64_t c) { s[c] = g[c] / diag[c]; });
    gs = compact_dot(g, s);
    double beta = std::max(0.0, (gs - g_sold) / gs_old);
    if (++since_restart >= st.restart_every) {
      beta = 0;
      since_restart = 0;
    }
    steepest = beta == 0;
    parallel_for(n, [&](int64_t c) { d[c] = -s[c] + beta * d[c]; });
    c0 = ct;
    ++res.iterations;
    if (on_iteration) on_iteration(res.iterations, c0);
  }
  if (c0 * norm < st.tolerance) res.converged = true;
  res.cost_per_particle = c0 * norm;
  // g may now point into gn_: make g_ hold the latest gradient for callers.
  if (g != g_.data()) std::swap(g_, gn_);
  return res;
}

}  // namespace drape
