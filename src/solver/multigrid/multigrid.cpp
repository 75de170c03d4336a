#include "solver/multigrid/multigrid.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>

namespace drape {

void Multigrid::build_levels(const std::vector<int64_t>& ids, int ni, int nj) {
  ++levels_built_;
  levels_.clear();
  levels_.emplace_back();
  levels_[0].ids = ids;
  std::vector<int32_t> scratch(size_t(ni) * nj, -1);
  int stride = 1;
  const int widest = std::max(ni, nj);
  while (int64_t(levels_.back().ids.size()) > s_.coarsest && 2 * stride < widest) {
    // Skip strides whose lines hold all the points already (an AMRC mesh's
    // coarse leaves): such a level would copy the one above.
    std::vector<int64_t> coarse = coarse_points(levels_.back().ids, ni, nj, stride);
    while (coarse.size() == levels_.back().ids.size() && 4 * stride < widest) {
      stride *= 2;
      coarse = coarse_points(levels_.back().ids, ni, nj, stride);
    }
    if (coarse.empty() || coarse.size() == levels_.back().ids.size()) break;
    levels_.back().stride = stride;
    Level& F = levels_.back();
    const int altered_levels = s_.interpolation == Interpolation::Fitted && s_.fit_cycles > 0 ? 1 : s_.smoothed_levels;
    const bool altered = s_.interpolation != Interpolation::Bilinear && int(levels_.size()) <= altered_levels;
    F.smoothed = altered && s_.interpolation == Interpolation::Smoothed;
    F.fitted = altered && s_.interpolation == Interpolation::Fitted;
    F.P0 = make_prolongation(F.ids, coarse, ni, nj, stride, scratch);
    if (F.fitted) {
      F.P = fitted_pattern(F.ids, coarse, ni, nj, stride, s_.fit_wide, scratch);
      for (size_t k = 0; k < F.ids.size(); ++k) scratch[F.ids[k]] = int32_t(k);
      F.fine_row.clear();
      for (int64_t p : coarse) F.fine_row.push_back(scratch[p]);
      for (int64_t p : F.ids) scratch[p] = -1;
    }
    levels_.emplace_back();
    levels_.back().ids = std::move(coarse);
    stride *= 2;
    levels_.back().stride = stride;
  }
  stats_.resize(levels_.size());  // cycles and seconds add up over the run, level by level
  for (size_t l = 0; l < levels_.size(); ++l) {
    Level& L = levels_[l];
    const size_t n = 3 * L.ids.size();
    L.b.assign(n, 0.0);
    L.x.assign(n, 0.0);
    L.r.assign(n, 0.0);
    L.lines = s_.smoothing == Smoothing::Line && int(l) < s_.line_levels;
    stats_[l].points = int64_t(L.ids.size());
    stats_[l].stride = L.stride;
  }
}

void Multigrid::setup(const BlockMatrix& A0, const std::vector<int64_t>& ids, int ni, int nj, uint64_t stamp) {
  setup_values(A0, setup_points(ids, ni, nj, stamp));
}

bool Multigrid::setup_points(const std::vector<int64_t>& ids, int ni, int nj, uint64_t stamp) {
  // The levels' points and transfers follow the particles alone: a new
  // pattern of K (self-contact's pairs) keeps them and rebuilds the products.
  const bool relevel = levels_.empty() || ni != ni_ || nj != nj_ || ids != levels_[0].ids;
  const bool fresh = relevel || stamp != stamp_ || stamp == 0 || int64_t(ids.size()) != rows_;
  if (relevel) build_levels(ids, ni, nj);
  else if (fresh) forget();  // a new pattern's smoothers start cold, as new levels' do
  ni_ = ni;
  nj_ = nj;
  stamp_ = stamp;
  rows_ = int64_t(ids.size());
  return fresh;
}

void Multigrid::setup_below(bool fresh, int64_t finest_blocks) {
  a0_ = nullptr;  // held by no one whole
  stats_[0].blocks = finest_blocks;
  build_from(1, fresh);
}

// Levels first to last: each one's operator (the Galerkin product of the
// one above, below `first`), smoother and transfer, or the factorisation.
void Multigrid::build_from(int first, bool fresh) {
  const int last = levels() - 1;
  for (int l = first; l <= last; ++l) {
    const double t0 = omp_get_wtime();
    if (l > first) galerkin_below(l, fresh);
    Level& L = levels_[l];
    if (l < last) {
      if (L.lines) L.line.setup(matrix(l), L.ids, ni_, nj_, L.stride, fresh);
      if (!L.lines || L.smoothed) L.smoother.setup(matrix(l), s_.degree, s_.ratio);
      if (L.smoothed)
        smooth_prolongation(matrix(l), L.smoother.dinv(), L.smoother.estimate(), L.P0, L.AP0, L.P, fresh);
      if (L.fitted) fit(l);
    } else {
      coarse_.factor(matrix(l), fresh);
    }
    stats_[l].blocks = matrix(l).blocks();
    stats_[l].setup_seconds += omp_get_wtime() - t0;
  }
}

// Level l's operator, P^T (A P) from the level above. A P's values are dead
// once the level below is built, so every level's A P keeps its pattern
// alone and writes its values into one workspace (the largest level's size,
// reused by each build: no allocation once sized).
void Multigrid::galerkin_below(int l, bool fresh) {
  Level& F = levels_[l - 1];
  F.AP.val.swap(ap_values_);
  // Never shrunk between builds: regrowing would zero what the product sets.
  if (!fresh && F.AP.val.size() < 9 * size_t(F.AP.blocks())) resize_keeping(F.AP.val, 9 * size_t(F.AP.blocks()));
  galerkin(matrix(l - 1), F.transfer(), F.AP, levels_[l].A, fresh);
  F.AP.val.swap(ap_values_);
}

// Level l's test vectors (pseudo-random on the finest fitted level, else
// the level above's on these points), relaxed on A e = 0 with a cold
// eigenvalue estimate (nothing carried from earlier builds: restarts stay
// bitwise), fitted; their values on the coarse points start the next level's.
void Multigrid::fit(int l) {
  Level& L = levels_[l];
  const BlockMatrix& A = matrix(l);
  if (l == 0 || !levels_[l - 1].fitted) random_vectors(A.rows, s_.fit_vectors, L.tests);
  if (s_.fit_cycles > 0 && l == 0) {
    cycle_vectors(A);
  } else {
    L.relax.forget();
    L.relax.setup(A, s_.fit_sweeps, s_.fit_ratio);
    relax_vectors(A, L.relax, s_.fit_vectors, L.tests, L.zero);
  }
  fit_prolongation(A, L.P0, L.fine_row, s_.fit_vectors, L.tests, s_.fit_tikhonov, s_.fit_keep_sums, s_.fit_full_blocks, L.P);
  Level& C = levels_[l + 1];
  if (C.fitted) inject_vectors(L.fine_row, A.rows, s_.fit_vectors, L.tests, C.tests);
}

// The finest level's test vectors relaxed by e <- e - M^-1 A e with the
// bilinear cycle M, fit_cycles times, then scaled to unit mean square.
void Multigrid::cycle_vectors(const BlockMatrix& A) {
  if (!probe_) probe_ = std::make_unique<Multigrid>();
  MultigridSettings b = s_;
  b.interpolation = Interpolation::Bilinear;
  probe_->set_settings(b);
  probe_->setup(A, levels_[0].ids, ni_, nj_, 0);
  Level& L = levels_[0];
  const int64_t m = 3 * A.rows;
  std::vector<double> ae(size_t(m), 0.0), c(size_t(m), 0.0);
  for (int k = 0; k < s_.fit_vectors; ++k) {
    double* e = &L.tests[size_t(k) * m];
    for (int it = 0; it < s_.fit_cycles; ++it) {
      A.multiply(e, ae.data());
      probe_->apply(ae.data(), c.data());
      for (int64_t i = 0; i < m; ++i) e[i] -= c[i];
    }
    double s = 0;
    for (int64_t i = 0; i < m; ++i) s += e[i] * e[i];
    const double scale = s > 0 ? std::sqrt(double(m) / s) : 0.0;
    for (int64_t i = 0; i < m; ++i) e[i] *= scale;
  }
}

void Multigrid::apply(const double* r, double* x) { cycle(0, r, x); }

void Multigrid::cycle(int l, const double* b, double* x) {
  const double t0 = omp_get_wtime();
  MultigridLevelStats& st = stats_[l];
  ++st.cycles;
  if (l == levels() - 1) {
    coarse_.solve(b, x);
    st.seconds += omp_get_wtime() - t0;
    return;
  }
  Level& L = levels_[l];
  Level& C = levels_[l + 1];
  const BlockMatrix& A = matrix(l);
  smooth(L, A, b, x, true);
  A.residual(b, x, L.r.data());
  restrict_to(L.transfer(), L.r.data(), C.b.data());
  const double t1 = omp_get_wtime();
  cycle(l + 1, C.b.data(), C.x.data());
  const double t2 = omp_get_wtime();
  prolong_add(L.transfer(), C.x.data(), x);
  smooth(L, A, b, x, false);
  st.seconds += (t1 - t0) + (omp_get_wtime() - t2);
}

}  // namespace drape

namespace drape {

// Pre-smoothing from x = 0; post-smoothing the adjoint (the line sweeps
// reversed): the cycle is symmetric.
void Multigrid::smooth(Level& L, const BlockMatrix& A, const double* b, double* x, bool pre) {
  if (L.lines) L.line.smooth(A, b, x, pre, pre, s_.line_sweeps);
  else L.smoother.smooth(A, b, x, pre);
}

}  // namespace drape

namespace drape {

void Multigrid::memory(MemoryTable& t) const {
  const char* o = "Multigrid";
  size_t ops = 0, transfers = 0, products = ap_values_.capacity() * sizeof(double), smoothers = 0, vectors = 0;
  for (const Level& l : levels_) {
    ops += held_bytes(l.A);
    transfers += held_bytes(l.P0.P) + held_bytes(l.P0.T) + held_bytes(l.P.P) + held_bytes(l.P.T);
    products += held_bytes(l.AP0) + held_bytes(l.AP);
    smoothers += l.smoother.held_bytes() + l.relax.held_bytes() + l.line.held_bytes();
    for (const auto* v : {&l.tests, &l.zero, &l.b, &l.x, &l.r}) vectors += v->capacity() * sizeof(double);
    vectors += (l.ids.capacity() + l.fine_row.capacity()) * sizeof(int64_t);
  }
  t.add(o, "coarse levels' operators (P^T A P)", ops);
  t.add(o, "prolongations and their transposes", transfers);
  t.add(o, "Galerkin workspaces (A P, its values)", products);
  t.add(o, "smoothers (inverse diagonal blocks, lines, vectors)", smoothers);
  t.add(o, "coarsest level's factor and ordering", coarse_.held_bytes());
  t.add(o, "levels' points and cycle vectors", vectors);
}

}  // namespace drape
