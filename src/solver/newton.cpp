#include "solver/newton.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <stdexcept>

#include "solver/multigrid/block_matrix.hpp"
#include "solver/slope_search.hpp"

namespace drape {

NewtonSolver::NewtonSolver(const Cloth& cloth, Minimizer& dots, Preconditioner pc)
    : c_(cloth), dots_(dots), pc_(pc) {}

// Sized at the first solve, not with the time loop: a run with the nonlinear
// CG (or the numeric gradient) never solves, and would hold them for nothing.
// Every vector holds positions only, in the evaluator's own numbering (the
// free particles first, in the compact order): d, r, s and the diagonal 3 a
// row the evaluator has room for, the product's operand p and K p 3 a
// particle of its numbering's room (the hanging and ghost particles the
// product reads and writes too). They change when those capacities do, at
// a mesh change (TimeLoop::mesh_changed calls fit_vectors).
void NewtonSolver::size_vectors(Evaluator& ev) {
  ev.numbering();  // held from here on: its room counts
  const size_t nc = 3 * ev.row_capacity(), nl = 3 * ev.local_capacity();
  if (r_.size() == nc && r_.capacity() == nc && p_.size() == nl && p_.capacity() == nl) return;
  for (auto* v : {&d_, &r_, &s_, &dc_}) std::vector<double>(nc, 0.0).swap(*v);  // exactly: a shrink gives memory back
  for (auto* v : {&p_, &kpc_}) std::vector<double>(nl, 0.0).swap(*v);
}

void NewtonSolver::release() {
  for (auto* v : {&d_, &r_, &s_, &p_, &kpc_, &dc_}) std::vector<double>().swap(*v);
}

void NewtonSolver::memory(MemoryTable& t) const {
  const char* o = "NewtonSolver";
  t.add(o, "d, r, s, diagonal (compact); p, K p (own numbering)",
        (d_.capacity() + r_.capacity() + s_.capacity() + p_.capacity() + kpc_.capacity() + dc_.capacity()) *
            sizeof(double));
  t.add(o, "ids", ids_);
  // Whole-level arrays, held only by the multigrid on several ranks: every
  // rank's rows of K (where the finest level is not divided), the whole
  // cycle's right-hand side and result and the rows' maps.
  t.add(o, "gathered K (multigrid, several ranks, finest level not divided)",
        kg_.start.capacity() * sizeof(int64_t) + kg_.col.capacity() * sizeof(int32_t) +
            kg_.val.capacity() * sizeof(double));
  t.add(o, "gathered right-hand side and result, the rows' maps (multigrid, several ranks)",
        (rg_.capacity() + xg_.capacity()) * sizeof(double) + ranks_.memory());
  t.add(o, "the finest level divided: ghosts, ring's K rows, K P and level-1 rows, smoother blocks, messages, vectors (several ranks)",
        div_.memory());
  t.add(o, "K assembled (the multigrid's finest level)", held_bytes(k_));
  mg_.memory(t);
}

// The compact vectors' row r and the evaluator's own numbering's index r
// are both the particle list's r-th free particle: checked when the lists
// change (the product then reads p and writes K p in place).
void NewtonSolver::check_numbering(const Evaluator& ev) {
  const ActiveLists& lists = ev.lists();
  if (numbered_stamp_ == lists.stamp && lists.stamp != 0) return;
  numbered_stamp_ = lists.stamp;
  const int64_t* items = lists.particles.items.data();
  const int64_t n = lists.particles.size();
  bool same = dots_.unknowns_below(c_.layout.tension()) == 3 * n;
  dots_.for_each_unknown(c_.layout.tension(), [&](int64_t c, int64_t k) {
    if (c % 3 == 0 && (c / 3 >= n || items[c / 3] != k / 3)) same = false;
  });
  if (!same) throw std::logic_error("NewtonSolver: compact vectors and particle list in different orders");
}

namespace {
// What the levels' point sets follow: the lists and their hanging particles.
uint64_t lists_stamp(const ActiveLists& l) { return l.stamp ^ (uint64_t(l.hanging.size()) << 48); }
// K's pattern changes with the lists and with self-contact's pair list.
uint64_t pattern_stamp(const Evaluator& ev) {
  return lists_stamp(ev.lists()) ^ (ev.self_contact().builds() << 24);
}
}  // namespace

// K assembled at z and the levels over it. The compact vectors number the
// free particles as the particle list does (tile, then index): the
// assembled rows' order, checked when the lists change.
// On several ranks every rank assembles its rows with global columns. Where
// the finest level can be divided (the bilinear finest P, point smoothing)
// no rank holds K whole: each builds the finest smoother and its level-1
// points' rows of R K P from its rows and a ring of others' (DividedLevel),
// and level 1, gathered, builds the levels below on every rank alike. Else
// (or with the division off) the levels are built from all ranks' rows of
// K, gathered in one rank's order, on every rank (RankRows).
void NewtonSolver::setup_multigrid(Evaluator& ev) {
  const ActiveLists& lists = ev.lists();
  const Reducer& red = dots_.reducer();
  const uint64_t stamp = red.sum_u64(pattern_stamp(ev));  // every rank's lists
  const bool renumber = ids_.size() != size_t(lists.particles.size()) || stamp != mg_stamp_;
  if (renumber) {
    ids_.assign(lists.particles.items.begin(), lists.particles.items.end());
    mg_stamp_ = stamp;  // in the compact order: check_numbering
  }
  if (red.ranks() == 1) {
    ev.assemble_stiffness(k_);
    mg_.setup(k_, ids_, c_.grid.ni, c_.grid.nj, stamp);
    return;
  }
  // Collective from here: stale is every rank's decision alike (multigrid_stale).
  if (renumber || ranks_.size() == 0) {
    ranks_.number(red, dots_.tiling(), ids_, c_.grid.n());
    std::vector<double>(size_t(3 * ranks_.size()), 0.0).swap(rg_);
    std::vector<double>(size_t(3 * ranks_.size()), 0.0).swap(xg_);
  }
  ev.assemble_stiffness(k_, &ranks_.column_of(), ranks_.size(), stamp);
  const bool fresh = mg_.setup_points(ranks_.ids(), c_.grid.ni, c_.grid.nj, stamp);
  const bool whole = !(divided_on_ && mg_.finest_divisible());
  if (whole) {
    ranks_.gather_matrix(red, k_, kg_);
    build_bytes_ = ranks_.matrix_bytes();
    mg_.setup_values(kg_, fresh);
  } else {
    if (kg_.rows != 0) kg_ = BlockMatrix();  // held by the gathered build alone
  }
  if (divided_on_ && mg_.finest_by_points()) {
    if (renumber || !div_.planned(mg_)) div_.plan(red, ranks_, k_, mg_);
    div_.build(red, ranks_, k_, mg_, whole, fresh);
    if (!whole) build_bytes_ = div_.build_bytes();
  }
  mg_builds_bytes_ += build_bytes_;
}

// The finest level divided over the ranks (DividedLevel), where it is
// smoothed by points; else the whole cycle gathered.
bool NewtonSolver::divided() const {
  return divided_on_ && dots_.reducer().ranks() > 1 && mg_.finest_by_points() && div_.planned(mg_);
}

namespace {
double process_cpu() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}
}  // namespace

void NewtonSolver::precondition(const double* r, double* s) {
  const double c0 = process_cpu();
  apply_preconditioner(r, s);
  pc_cpu_ += process_cpu() - c0;
}

void NewtonSolver::apply_preconditioner(const double* r, double* s) {
  if (dots_.reducer().ranks() == 1) {
    mg_.apply(r, s);
    return;
  }
  if (divided()) {
    div_.apply(dots_.reducer(), k_, mg_, r, s);
    mg_cycles_bytes_ += div_.gathered_bytes();
    return;
  }
  ranks_.gather(dots_.reducer(), r, rg_.data());
  mg_cycles_bytes_ += ranks_.vector_bytes();
  mg_.apply(rg_.data(), xg_.data());
  ranks_.take_mine(xg_.data(), s);
}

// A V-cycle built on K at an earlier Newton iteration of the same step still
// preconditions well (K moves little within a step), and its set-up costs
// several products: it is rebuilt at each minimize()'s first solve (so a
// restarted run rebuilds where the uninterrupted one did), when the lists
// changed, and when the last solve took more than twice the iterations of
// the first solve on this build.
bool NewtonSolver::multigrid_stale(const Evaluator& ev) const {
  if (mg_solves_ == 0 || mg_last_ > std::max(4, 2 * mg_first_)) return true;
  return dots_.reducer().sum_u64(pattern_stamp(ev)) != mg_stamp_;  // every rank's lists: one decision
}

// Preconditioned CG for K d = -rho. Its vectors are compact: the free
// particles' positions numbered in tile order (Minimizer::tile_sums' c), so
// that a coarse mesh's few unknowns lie together in memory instead of one
// triple per cache line. The product's operand p and its result K p (and
// the diagonal, first) run on past the free particles into the hanging and
// ghost ones of the evaluator's own numbering, which the product reads and
// writes. The preconditioner: the diagonal (each particle's three entries
// scaled by its block's trace / 3), or one multigrid V-cycle on K assembled.
// Stops at |r| <= rel_tol |b| or after `budget` iterations; returns the count.
int NewtonSolver::linear_solve(Evaluator& ev, const double* z, int budget, double rel_tol,
                               Timers& tm) {
  size_vectors(ev);
  check_numbering(ev);
  double *d = d_.data(), *r = r_.data(), *s = s_.data(), *p = p_.data(), *kp = kpc_.data(),
         *dc = dc_.data();
  // Past the free particles p is read, never updated: hanging and ghost
  // entries are interpolated and received, every other one (a clamped
  // particle's) must be 0. The diagonal lands in K p's vector: it is read
  // once, into dc, before the first product overwrites it.
  std::fill(p_.begin() + 3 * ev.lists().particles.size(), p_.end(), 0.0);
  double* diag = kp;
  const double* rho = ev.residual().data();  // in the compact order
  const int64_t end = c_.layout.tension();
  const bool mg = pc_ == Preconditioner::Multigrid;
  {
    ScopedPhase ph(tm, kScaling);
    ev.stiffness_diagonal_local(z, diag);
    if (mg && multigrid_stale(ev)) {
      const double c0 = process_cpu();
      setup_multigrid(ev);
      build_cpu_ += process_cpu() - c0;
      mg_solves_ = 0;
      ++mg_builds_;
    }
  }
  double target, rs;
  if (!mg) {
    ScopedPhase ph(tm, kVector);
    double sums[2];  // b.b, r.s with b = -rho: one pass, the diagonal's s on the way
    dots_.compact_sums<2>(end, [&](int64_t c, double* acc) {
      const double b = -rho[c];
      dc[c] = diag[c];
      d[c] = 0;
      r[c] = b;
      s[c] = r[c] / dc[c];
      p[c] = s[c];
      acc[0] += b * b;
      acc[1] += r[c] * s[c];
    }, sums);
    target = rel_tol * rel_tol * sums[0];
    rs = sums[1];
  } else {
    double bb;
    {
      ScopedPhase ph(tm, kVector);
      dots_.compact_sums<1>(end, [&](int64_t c, double* acc) {
        const double b = -rho[c];
        d[c] = 0;
        r[c] = b;
        acc[0] += b * b;
      }, &bb);
    }
    {
      ScopedPhase ph(tm, kPrecondition);
      precondition(r, s);
    }
    ScopedPhase ph(tm, kVector);
    dots_.compact_sums<1>(end, [&](int64_t c, double* acc) {
      p[c] = s[c];
      acc[0] += r[c] * s[c];
    }, &rs);
    target = rel_tol * rel_tol * bb;
  }
  int it = 0;
  while (it < budget) {
    {
      ScopedPhase g(tm, kGradient);  // one stiffness product: a gradient's worth of work
      ev.stiffness_product_local(z, p, kp);
    }
    double sums[2];  // r.r, r.s
    {
      ScopedPhase ph(tm, kVector);
      double pkp;
      dots_.compact_sums<1>(end, [&](int64_t c, double* acc) { acc[0] += p[c] * kp[c]; }, &pkp);
      if (!(pkp > 0)) break;  // K is positive definite by construction; guard anyway
      const double a = rs / pkp;
      if (mg)  // the step, the residual and its norm; s from the V-cycle below
        dots_.compact_sums<1>(end, [&](int64_t c, double* acc) {
          d[c] += a * p[c];
          r[c] -= a * kp[c];
          acc[0] += r[c] * r[c];
        }, sums);
      else  // one pass: with the diagonal's s and both dot products (s wasted on the last iteration only)
        dots_.compact_sums<2>(end, [&](int64_t c, double* acc) {
          d[c] += a * p[c];
          r[c] -= a * kp[c];
          s[c] = r[c] / dc[c];
          acc[0] += r[c] * r[c];
          acc[1] += r[c] * s[c];
        }, sums);
    }
    ++it;
    if (sums[0] <= target || it == budget) break;  // no V-cycle for a direction never taken
    if (mg) {
      {
        ScopedPhase ph(tm, kPrecondition);
        precondition(r, s);
      }
      ScopedPhase ph(tm, kVector);
      dots_.compact_sums<1>(end, [&](int64_t c, double* acc) { acc[0] += r[c] * s[c]; }, sums + 1);
    }
    ScopedPhase ph(tm, kVector);
    const double rs1 = sums[1];
    const double beta = rs1 / rs;
    rs = rs1;
    dots_.for_each_unknown(end, [&](int64_t c, int64_t) { p[c] = s[c] + beta * p[c]; });
  }
  if (mg) {
    if (mg_solves_++ == 0) mg_first_ = it;
    mg_last_ = it;
  }
  return it;
}

// The step's energy slope along the Newton direction at the last evaluated
// z: d . rho, both in the compact order (a fixed-order sum, the same on
// every rank and thread count).
double NewtonSolver::slope(const Evaluator& ev) {
  const double* rho = ev.residual().data();
  const double* d = d_.data();
  double g;
  dots_.compact_sums<1>(c_.layout.tension(), [&](int64_t c, double* acc) { acc[0] += rho[c] * d[c]; }, &g);
  return g;
}

// SlopeSearch's trials from a = 1 (g0: the slope at z): true with z at the
// accepted one (its cost in res.cost and c0). False when its trials ran out or the direction does
// not descend; z is then at some trial, and the caller backtracks.
template <class Trial>
bool NewtonSolver::slope_search(Evaluator& ev, double g0, Trial&& trial, CgResult& res, double& c0) {
  SlopeSearch search(g0);
  if (!search.usable()) return false;
  double a = 1.0;
  for (int t = 0; t < SlopeSearch::kTrials && a > 0; ++t) {
    const CostTerms cost = trial(a);
    const double g = slope(ev);
    a = search.accepts(g) ? 0.0 : search.next(a, g);
    // Flat enough, or the longest step and still descending (a = 0 either
    // way): taken if its cost is finite, and in the second case lower.
    if (a == 0 && std::isfinite(cost.total()) && (search.accepts(g) || cost.total() < c0)) {
      res.cost = cost;
      c0 = cost.total();
      return true;
    }
  }
  return false;
}

// The active-set rounds (BandActiveSet): the full step is tried; while its
// slope is not within SlopeSearch::kAccept of the slope at z (it over- or
// undershoots, the bands' kinks crossed on the wrong tangent), z is
// evaluated again, the elements that landed on another branch take their
// secant stiffness, and the step is solved again, at most kKinkRounds times.
// Global decisions from fixed-order sums only (the slopes): every rank takes
// the same rounds. Returns the slope at z along the final direction; the
// line search follows, its first trial (a = 1) the last round's, kept.
template <class Trial>
double NewtonSolver::through_kinks(Evaluator& ev, double* z, double g0, Trial&& trial, double& last_a,
                                   CgResult& res, const CgSettings& st, double eta, Timers& tm) {
  constexpr int kKinkRounds = 2;
  const int64_t end = c_.layout.tension();
  double* zt = r_.data();
  ev.branches().next_iteration();
  for (int round = 0; round < kKinkRounds && res.iterations < st.max_iterations; ++round) {
    trial(1.0);
    if (std::fabs(slope(ev)) <= SlopeSearch::kAccept * std::fabs(g0)) break;
    // Back to z: its residual and kept numbers, then the landed branches' slopes.
    dots_.for_each_unknown(end, [&](int64_t c, int64_t k) { z[k] = zt[c]; });
    ev.branches().at_z();
    {
      ScopedPhase ph(tm, kLineSearch);
      ++res.evaluations;
      ev.settled_cost(z);
      last_a = -1;  // the kept trial is not where the evaluator is
    }
    ev.kink_tangents();
    const int used = linear_solve(ev, z, st.max_iterations - res.iterations, eta, tm);
    res.iterations += std::max(1, used);
    // The solve used the positions' save as its residual: z holds them.
    dots_.for_each_unknown(end, [&](int64_t c, int64_t k) { zt[c] = z[k]; });
    g0 = slope(ev);
  }
  return g0;
}

// Inexact Newton's forcing term, the linear solve's relative tolerance.
// By default a loose solve far from the solution, tighter near it: the
// residual's root mean square (in particle weights), within [1e-3, 0.1].
// Adaptive (Eisenstat and Walker's second choice): 0.9 times the square of
// the last iteration's residual reduction. Through the bands' kinks Newton
// converges linearly at best, and a tight solve buys a direction that the
// wrong branch's tangent bends anyway; this forcing is as tight as the
// iterations lately made use of. While large it falls no faster than
// 0.9 eta_prev^2 (one lucky iteration does not make the next solve tight),
// and it never asks more than reaching the tolerance needs (half the
// residual reduction left to it). At most 0.9: the step's first solve
// (no reduction yet) takes the residual's size, as the default.
double NewtonSolver::forcing(const CgSettings& st, double c, double c_prev, double eta_prev) {
  if (!st.adaptive_forcing) return std::clamp(std::sqrt(c), 1e-3, 0.1);
  constexpr double kGamma = 0.9, kMin = 1e-3, kMax = 0.9;
  if (c_prev < 0) return std::clamp(std::sqrt(c), kMin, kMax);
  double eta = kGamma * c / c_prev;  // c is the squared residual: (|r_k| / |r_k-1|)^2
  if (kGamma * eta_prev * eta_prev > 0.1) eta = std::max(eta, kGamma * eta_prev * eta_prev);
  eta = std::max(eta, 0.5 * std::sqrt(st.tolerance / c));
  return std::clamp(eta, kMin, kMax);
}

CgResult NewtonSolver::minimize(Evaluator& ev, double* z, const CgSettings& st, Timers& tm,
                                const std::function<void(int, double)>& on_iteration) {
  const double norm = 1.0 / double(std::max<int64_t>(1, st.free_particles));
  CgResult res;
  // Branches noted at z's slot first (BandActiveSet), the trials' beside them.
  const bool kinks = st.active_set && ev.branches().enabled();
  if (kinks) ev.branches().at_z();
  if (st.settled_at_start) {
    res.cost = *st.settled_at_start;
  } else {
    ScopedPhase ph(tm, kGradient);
    res.cost = ev.settled_cost(z);
    res.evaluations = 1;
  }
  double c0 = res.cost.total();
  size_vectors(ev);
  // The free particles' positions before the line search's trials, in the
  // linear solve's residual: it is dead from the solve's end to the next.
  double* zt = r_.data();
  const int64_t end = c_.layout.tension();  // the positions: Newton's unknowns
  if (dots_.unknowns_below(end) > int64_t(r_.size()))  // 3 per owned particle at most
    throw std::logic_error("NewtonSolver: more unknowns than the compact vectors hold");
  mg_solves_ = 0;  // a new step (or a retry): the V-cycle is built afresh,
  mg_.forget();    // from this step's K alone (restarts stay bitwise)
  div_.forget();
  double c_prev = -1, eta_prev = 0;  // the last iteration's cost and forcing (none yet: -1)
  while (std::isfinite(c0) && c0 * norm >= st.tolerance && res.iterations < st.max_iterations) {
    if (st.stop_requested && st.stop_requested()) {
      res.stopped = true;
      break;
    }
    const double eta = forcing(st, c0 * norm, c_prev * norm, eta_prev);
    c_prev = c0;
    eta_prev = eta;
    const int used = linear_solve(ev, z, st.max_iterations - res.iterations, eta, tm);
    res.iterations += std::max(1, used);
    ++res.newton_iterations;
    // d_ solves K d = -rho, rho the evaluator's residual in F0 units: the
    // position step is d * F0.
    const double scale = ev.force_scale();
    // Trials in place: each evaluation brings z's ghosts and hanging particles
    // up to date and sets the element forces from the positions, so only the
    // free particles' positions are saved and restored (a whole-array copy
    // would cost the finest mesh's price on a coarse one).
    dots_.for_each_unknown(end, [&](int64_t c, int64_t k) { zt[c] = z[k]; });
    double g0 = kinks || st.slope_search ? slope(ev) : 0.0;
    // The last trial's step and cost: the active-set rounds' last full step
    // is the line search's first trial (z and the evaluator still there).
    double last_a = -1;
    CostTerms last;
    auto trial = [&](double a) {
      if (a == last_a) return last;
      ScopedPhase ph(tm, kLineSearch);
      dots_.for_each_unknown(end, [&](int64_t c, int64_t k) { z[k] = zt[c] + a * scale * d_[c]; });
      ++res.evaluations;
      if (kinks) ev.branches().at_trial();
      last = ev.settled_cost(z);
      last_a = a;
      return last;
    };
    if (kinks) g0 = through_kinks(ev, z, g0, trial, last_a, res, st, eta, tm);
    bool accepted = st.slope_search && slope_search(ev, g0, trial, res, c0);
    for (double a = 1.0; !accepted && a > 1e-4; a *= 0.5) {
      const CostTerms t = trial(a);
      if (std::isfinite(t.total()) && t.total() < c0) {
        res.cost = t;
        c0 = t.total();
        accepted = true;
      }
    }
    if (accepted && kinks) ev.branches().accept_trial();  // the last trial evaluated
    if (!accepted) {
      // Back to where the line search began; z's residual buffers with it.
      dots_.for_each_unknown(end, [&](int64_t c, int64_t k) { z[k] = zt[c]; });
      res.cost = ev.settled_cost(z);
      res.stalled = true;
      break;
    }
    if (on_iteration) on_iteration(res.iterations, c0);
  }
  res.converged = c0 * norm < st.tolerance;
  res.cost_per_particle = c0 * norm;
  return res;
}

}  // namespace drape
