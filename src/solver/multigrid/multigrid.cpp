#include "solver/multigrid/multigrid.hpp"

#include <omp.h>

#include <algorithm>

namespace drape {

void Multigrid::build_levels(const std::vector<int64_t>& ids, int ni, int nj) {
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
    levels_.back().smoothed =
        s_.interpolation != Interpolation::Bilinear && int(levels_.size()) <= s_.smoothed_levels;
    levels_.back().P0 = make_prolongation(levels_.back().ids, coarse, ni, nj, stride, scratch);
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
    stats_[l].points = int64_t(L.ids.size());
    stats_[l].stride = L.stride;
  }
}

void Multigrid::setup(const BlockMatrix& A0, const std::vector<int64_t>& ids, int ni, int nj, uint64_t stamp) {
  a0_ = &A0;
  const bool fresh = stamp != stamp_ || stamp == 0 || A0.rows != rows_;
  if (fresh) build_levels(ids, ni, nj);
  stamp_ = stamp;
  rows_ = A0.rows;
  const int last = levels() - 1;
  for (int l = 0; l <= last; ++l) {
    const double t0 = omp_get_wtime();
    if (l > 0) galerkin(matrix(l - 1), levels_[l - 1].transfer(), levels_[l - 1].AP, levels_[l].A, fresh);
    Level& L = levels_[l];
    if (l < last) {
      if (s_.smoothing == Smoothing::Line) L.line.setup(matrix(l), L.ids, ni, nj, L.stride, fresh);
      if (s_.smoothing == Smoothing::Point || L.smoothed) L.smoother.setup(matrix(l), s_.degree, s_.ratio);
      if (L.smoothed)
        smooth_prolongation(matrix(l), L.smoother.dinv(), L.smoother.estimate(), L.P0, L.AP0, L.P, fresh);
    } else {
      coarse_.factor(matrix(l), fresh);
    }
    stats_[l].blocks = matrix(l).blocks();
    stats_[l].setup_seconds += omp_get_wtime() - t0;
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
  if (s_.smoothing == Smoothing::Line) L.line.smooth(A, b, x, pre, pre, s_.line_sweeps);
  else L.smoother.smooth(A, b, x, pre);
}

}  // namespace drape
