#include "solver/multigrid/line_smoother.hpp"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <tuple>

namespace drape {

namespace {
// A grid coordinate's line on a level of stride s: line k at k s, and the far
// border (not a multiple of s) on the next.
inline int level_line(int g, int s) { return (g + s - 1) / s; }

// out -= a b^T (3 x 3, row-major).
inline void sub_product_transposed(const double* a, const double* b, double* out) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out[3 * i + j] -= a[3 * i] * b[3 * j] + a[3 * i + 1] * b[3 * j + 1] + a[3 * i + 2] * b[3 * j + 2];
}

// out = a b (3 x 3).
inline void product(const double* a, const double* b, double* out) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

// y -= B^T x for one 3 x 3 block.
inline void sub_transposed_times(const double* b, const double* x, double* y) {
  for (int i = 0; i < 3; ++i) y[i] -= b[i] * x[0] + b[3 + i] * x[1] + b[6 + i] * x[2];
}
}  // namespace

void LineSmoother::find_lines(Direction& d, const BlockMatrix& A, const std::vector<int64_t>& ids, int nj, int stride,
                              int dir) {
  const int64_t n = int64_t(ids.size());
  // (across, along, row): rows sorted line by line, along each line.
  std::vector<std::tuple<int, int, int32_t>> key(static_cast<size_t>(n));
  for (int64_t r = 0; r < n; ++r) {
    const int gi = level_line(int(ids[r] / nj), stride), gj = level_line(int(ids[r] % nj), stride);
    key[r] = dir == 0 ? std::make_tuple(gi, gj, int32_t(r)) : std::make_tuple(gj, gi, int32_t(r));
  }
  std::sort(key.begin(), key.end());
  d.order.resize(size_t(n));
  d.line_start.assign(1, 0);
  std::vector<int32_t> across_of_line;
  std::vector<int64_t> position(static_cast<size_t>(n));  // row -> position in order
  std::vector<int32_t> line_of(static_cast<size_t>(n));
  for (int64_t q = 0; q < n; ++q) {
    const auto& [across, along, row] = key[q];
    if (q > 0 && std::get<0>(key[q - 1]) != across) d.line_start.push_back(q);
    if (q == 0 || std::get<0>(key[q - 1]) != across) across_of_line.push_back(across);
    d.order[q] = row;
    position[row] = q;
    line_of[row] = int32_t(across_of_line.size() - 1);
  }
  d.line_start.push_back(n);
  // The band (positions along a line) and the widest coupling across lines.
  int band = 1, across = 0;
  for (int64_t r = 0; r < n; ++r)
    for (int64_t k = A.start[r]; k < A.start[r + 1]; ++k) {
      const int32_t c = A.col[k];
      const int dl = std::abs(across_of_line[line_of[r]] - across_of_line[line_of[c]]);
      if (dl == 0) band = std::max<int>(band, int(std::abs(position[r] - position[c])));
      across = std::max(across, dl);
    }
  d.band = band;
  d.colours = across + 1;
  const int64_t lines = int64_t(across_of_line.size());
  d.by_colour.clear();
  d.colour_start.assign(1, 0);
  for (int c = 0; c < d.colours; ++c) {
    for (int64_t l = 0; l < lines; ++l)
      if (across_of_line[l] % d.colours == c) d.by_colour.push_back(int32_t(l));
    d.colour_start.push_back(int64_t(d.by_colour.size()));
  }
  std::vector<std::pair<int32_t, int32_t>> rows;  // (row, position) of one colour
  d.colour_rows.clear();
  d.colour_pos.clear();
  d.colour_row_start.assign(1, 0);
  for (int c = 0; c < d.colours; ++c) {
    rows.clear();
    for (int64_t k = d.colour_start[c]; k < d.colour_start[c + 1]; ++k)
      for (int64_t q = d.line_start[d.by_colour[k]]; q < d.line_start[d.by_colour[k] + 1]; ++q)
        rows.emplace_back(d.order[q], int32_t(q));
    std::sort(rows.begin(), rows.end());
    for (const auto& [row, q] : rows) {
      d.colour_rows.push_back(row);
      d.colour_pos.push_back(q);
    }
    d.colour_row_start.push_back(int64_t(d.colour_rows.size()));
  }
  d.dinv.assign(9 * size_t(n), 0.0);
  d.low.assign(9 * size_t(band) * size_t(n), 0.0);
}

// Block L D L^T of each line's band, with W = L D: W(k, j) = A(k, j) -
// sum_{i < j} L(k, i) W(j, i)^T, L(k, j) = W(k, j) D(j)^-1, D(k) = A(k, k) -
// sum_{i < k} L(k, i) W(k, i)^T.
void LineSmoother::factor(Direction& d, const BlockMatrix& A) {
  const int band = d.band;
  const int64_t lines = int64_t(d.line_start.size()) - 1;
  w_.resize(d.low.size());
  bool ok = true;
#pragma omp parallel for schedule(static) reduction(&& : ok)
  for (int64_t l = 0; l < lines; ++l) {
    const int64_t q0 = d.line_start[l], q1 = d.line_start[l + 1];
    for (int64_t q = q0; q < q1; ++q) {
      const int32_t row = d.order[q];
      double* lq = &d.low[9 * size_t(band) * q];
      double* wq = &w_[9 * size_t(band) * q];
      for (int dd = band; dd >= 1; --dd) {
        double* w = wq + 9 * (dd - 1);
        if (q - dd < q0) {
          std::fill(w, w + 9, 0.0);
          std::fill(lq + 9 * (dd - 1), lq + 9 * dd, 0.0);
          continue;
        }
        const int64_t j = q - dd;
        const double* a = A.block(row, d.order[j]);
        if (a) to_row_major(a, w);
        else std::fill(w, w + 9, 0.0);
        for (int e = dd + 1; e <= band && q - e >= q0; ++e)  // i = q - e < j
          sub_product_transposed(lq + 9 * (e - 1), &w_[9 * (size_t(band) * j + (e - dd - 1))], w);
        product(w, &d.dinv[9 * j], lq + 9 * (dd - 1));
      }
      double diag[9];
      const double* a = A.block(row, row);
      if (a) to_row_major(a, diag);
      else std::fill(diag, diag + 9, 0.0);
      for (int dd = 1; dd <= band && q - dd >= q0; ++dd) sub_product_transposed(lq + 9 * (dd - 1), wq + 9 * (dd - 1), diag);
      ok = ok && invert_block(diag, &d.dinv[9 * q]);
    }
  }
  if (!ok) throw std::runtime_error("multigrid: a grid line's block is singular");
}

void LineSmoother::setup(const BlockMatrix& A, const std::vector<int64_t>& ids, int ni, int nj, int stride,
                         bool pattern) {
  (void)ni;
  for (int dir = 0; dir < 2; ++dir) {
    if (pattern || dir_[dir].order.size() != size_t(A.rows)) find_lines(dir_[dir], A, ids, nj, stride, dir);
    factor(dir_[dir], A);
  }
  r_.assign(3 * size_t(A.rows), 0.0);
}

// v (3 a position, the line's stretch of r_) = the line's band^-1 v.
void LineSmoother::solve_line(const Direction& d, int64_t line, double* v) const {
  const int band = d.band;
  const int64_t q0 = d.line_start[line], q1 = d.line_start[line + 1];
  for (int64_t q = q0; q < q1; ++q)  // L y = v
    for (int dd = 1; dd <= band && q - dd >= q0; ++dd)
      add_block_times(&d.low[9 * (size_t(band) * q + dd - 1)], v + 3 * (q - dd), -1.0, v + 3 * q);
  for (int64_t q = q0; q < q1; ++q) {  // z = D^-1 y
    double y[3] = {v[3 * q], v[3 * q + 1], v[3 * q + 2]};
    v[3 * q] = v[3 * q + 1] = v[3 * q + 2] = 0;
    add_block_times(&d.dinv[9 * q], y, 1.0, v + 3 * q);
  }
  for (int64_t q = q1 - 1; q >= q0; --q)  // L^T x = z
    for (int dd = 1; dd <= band && q + dd < q1; ++dd)
      sub_transposed_times(&d.low[9 * (size_t(band) * (q + dd) + dd - 1)], v + 3 * (q + dd), v + 3 * q);
}

// One colour's lines: the residuals on its rows from the current x, then
// each line's exact correction (lines of a colour share no coupling), then x
// updated: each row's result is the same on any thread count.
void LineSmoother::sweep_colour(const Direction& d, int colour, const BlockMatrix& A, const double* b, double* x,
                                bool x_zero) {
  double* __restrict r = r_.data();
  const int64_t k0 = d.colour_row_start[colour], k1 = d.colour_row_start[colour + 1];
#pragma omp parallel
  {
#pragma omp for schedule(static)
    for (int64_t k = k0; k < k1; ++k) {
      const int64_t row = d.colour_rows[k];
      double y0 = b[3 * row], y1 = b[3 * row + 1], y2 = b[3 * row + 2];
      if (!x_zero) {
        const double* __restrict a = A.val.data() + 9 * A.start[row];
        for (int64_t e = A.start[row], end = A.start[row + 1]; e < end; ++e, a += 9) {
          const double* xc = x + 3 * int64_t(A.col[e]);
          const double x0 = xc[0], x1 = xc[1], x2 = xc[2];
          y0 -= a[entry(0, 0)] * x0 + a[entry(0, 1)] * x1 + a[entry(0, 2)] * x2;
          y1 -= a[entry(1, 0)] * x0 + a[entry(1, 1)] * x1 + a[entry(1, 2)] * x2;
          y2 -= a[entry(2, 0)] * x0 + a[entry(2, 1)] * x1 + a[entry(2, 2)] * x2;
        }
      }
      double* rq = r + 3 * int64_t(d.colour_pos[k]);
      rq[0] = y0;
      rq[1] = y1;
      rq[2] = y2;
    }
#pragma omp for schedule(static)
    for (int64_t k = d.colour_start[colour]; k < d.colour_start[colour + 1]; ++k) solve_line(d, d.by_colour[k], r);
#pragma omp for schedule(static)
    for (int64_t k = k0; k < k1; ++k) {
      const int64_t row = d.colour_rows[k];
      const double* rq = r + 3 * int64_t(d.colour_pos[k]);
      for (int c = 0; c < 3; ++c) x[3 * row + c] += rq[c];
    }
  }
}

void LineSmoother::smooth(const BlockMatrix& A, const double* b, double* x, bool zero, bool forward, int sweeps) {
  if (zero) std::fill(x, x + 3 * A.rows, 0.0);
  bool x_zero = zero;
  for (int s = 0; s < sweeps; ++s)
    for (int step = 0; step < 2; ++step) {
      const Direction& d = dir_[forward ? step : 1 - step];
      for (int k = 0; k < d.colours; ++k) {
        sweep_colour(d, forward ? k : d.colours - 1 - k, A, b, x, x_zero);
        x_zero = false;
      }
    }
}

}  // namespace drape
