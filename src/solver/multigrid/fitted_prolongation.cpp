#include "solver/multigrid/fitted_prolongation.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <utility>

namespace drape {

namespace {

inline bool on_lines(int i, int n, int s) { return i % s == 0 || i == n - 1; }

// Grid line i's coarse neighbours (lines of stride 2s): itself where it is
// one (and, where `wide`, the coarse lines either side), else the two
// either side.
int coarse_lines(int i, int n, int s, bool wide, int out[3]) {
  if (!on_lines(i, n, 2 * s)) {
    out[0] = i - s;
    out[1] = std::min(i + s, n - 1);
    return 2;
  }
  int k = 0;
  if (wide && i > 0) out[k++] = (i == n - 1 && i % (2 * s) != 0) ? i / (2 * s) * (2 * s) : i - 2 * s;
  out[k++] = i;
  if (wide && i < n - 1) out[k++] = std::min(i + 2 * s, n - 1);
  return k;
}

uint64_t mix(uint64_t x) {  // splitmix64's finaliser
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

constexpr int kMaxNeighbours = 6;
constexpr int kMaxUnknowns = 3 * kMaxNeighbours;
using Gram = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxUnknowns, kMaxUnknowns>;
using Rhs = Eigen::Matrix<double, Eigen::Dynamic, 3, 0, kMaxUnknowns, 3>;

// Component i of fine row f from component i of its k coarse neighbours
// (`cols`): the diagonal entries of the row's blocks, `out` (9 a block).
// min sum_t w_t (x_f - u_t . c)^2 + mu |c - w0|^2, and where `keep_sums`
// sum c = rowsum (a Lagrange multiplier: c = G^-1 (r - l 1)).
void fit_component(const std::vector<double>& v, int count, int64_t m, const std::vector<double>& weight,
                   const std::vector<int64_t>& fine_row, const int32_t* cols, int k, int64_t f, int i,
                   const double* w0, double rowsum, double tikhonov, bool keep_sums, double* out) {
  using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxNeighbours, kMaxNeighbours>;
  using Vec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxNeighbours, 1>;
  Small G = Small::Zero(k, k);
  Vec r = Vec::Zero(k);
  double u[kMaxNeighbours];
  for (int t = 0; t < count; ++t) {
    const double* x = &v[size_t(t) * m];
    for (int b = 0; b < k; ++b) u[b] = x[3 * fine_row[cols[b]] + i];
    for (int a = 0; a < k; ++a) {
      for (int c = 0; c < k; ++c) G(a, c) += weight[t] * u[a] * u[c];
      r(a) += weight[t] * u[a] * x[3 * f + i];
    }
  }
  double mu = 0;
  for (int a = 0; a < k; ++a) mu += G(a, a);
  mu = tikhonov * (mu > 0 ? mu / k : 1.0);
  for (int a = 0; a < k; ++a) {
    G(a, a) += mu;
    r(a) += mu * w0[a];
  }
  Eigen::LLT<Small> llt(G);
  Vec c = llt.solve(r);
  if (keep_sums) {
    const Vec g1 = llt.solve(Vec::Ones(k));
    c -= ((c.sum() - rowsum) / g1.sum()) * g1;
  }
  for (int b = 0; b < k; ++b) {
    for (int j = 0; j < 3; ++j) out[9 * b + entry(i, j)] = 0.0;
    out[9 * b + 4 * i] = c(b);
  }
}

}  // namespace

Prolongation fitted_pattern(const std::vector<int64_t>& fine_ids, const std::vector<int64_t>& coarse_ids, int ni,
                            int nj, int stride, bool wide, std::vector<int32_t>& scratch) {
  Prolongation out;
  BlockMatrix& P = out.P;
  P.rows = int64_t(fine_ids.size());
  for (size_t k = 0; k < coarse_ids.size(); ++k) scratch[coarse_ids[k]] = int32_t(k);
  P.start.assign(size_t(P.rows) + 1, 0);
  for (int64_t f = 0; f < P.rows; ++f) {
    const int64_t p = fine_ids[f];
    std::vector<int32_t> row;
    if (scratch[p] >= 0) {
      row.push_back(scratch[p]);  // a coarse point: injection
    } else {
      int ii[3], jj[3];
      const int a_n = coarse_lines(int(p / nj), ni, stride, wide, ii);
      const int b_n = coarse_lines(int(p % nj), nj, stride, wide, jj);
      for (int a = 0; a < a_n; ++a)
        for (int b = 0; b < b_n; ++b) {
          const int32_t c = scratch[int64_t(ii[a]) * nj + jj[b]];
          if (c >= 0) row.push_back(c);
        }
      std::sort(row.begin(), row.end());
    }
    P.col.insert(P.col.end(), row.begin(), row.end());
    P.start[f + 1] = int64_t(P.col.size());
  }
  P.val.assign(9 * P.col.size(), 0.0);
  for (int64_t p : coarse_ids) scratch[p] = -1;
  transpose(P, int64_t(coarse_ids.size()), out.T);
  return out;
}

void random_vectors(int64_t rows, int count, std::vector<double>& v) {
  const int64_t m = 3 * rows;
  v.resize(size_t(count) * m);
  for (int64_t k = 0; k < int64_t(v.size()); ++k) v[k] = double(mix(uint64_t(k)) >> 11) * 0x1.0p-52 - 1.0;
}

void relax_vectors(const BlockMatrix& A, Chebyshev& relax, int count, std::vector<double>& v, std::vector<double>& zero) {
  const int64_t m = 3 * A.rows;
  zero.assign(size_t(m), 0.0);
  for (int k = 0; k < count; ++k) {
    double* x = &v[size_t(k) * m];
    relax.smooth(A, zero.data(), x, false);
    double s = 0;
    for (int64_t i = 0; i < m; ++i) s += x[i] * x[i];
    const double scale = s > 0 ? std::sqrt(double(m) / s) : 0.0;
    for (int64_t i = 0; i < m; ++i) x[i] *= scale;
  }
}

void inject_vectors(const std::vector<int64_t>& fine_row, int64_t fine_rows, int count, const std::vector<double>& v,
                    std::vector<double>& out) {
  const int64_t mc = 3 * int64_t(fine_row.size()), mf = 3 * fine_rows;
  out.resize(size_t(count) * mc);
  for (int k = 0; k < count; ++k)
    for (size_t c = 0; c < fine_row.size(); ++c)
      for (int i = 0; i < 3; ++i) out[k * mc + 3 * c + i] = v[k * mf + 3 * fine_row[c] + i];
}

void fit_prolongation(const BlockMatrix& A, const Prolongation& P0, const std::vector<int64_t>& fine_row, int count,
                      const std::vector<double>& v, double tikhonov, bool keep_sums, bool full_blocks,
                      Prolongation& P) {
  const int64_t rows = A.rows, m = 3 * rows;
  // Each vector's weight: the inverse of its Rayleigh quotient (the lower
  // its energy, the more the coarse space must hold it), the lowest 1.
  std::vector<double> weight(static_cast<size_t>(count)), av(static_cast<size_t>(m));
  double least = 0;
  for (int k = 0; k < count; ++k) {
    const double* x = &v[size_t(k) * m];
    A.multiply(x, av.data());
    double e = 0, s = 0;
    for (int64_t i = 0; i < m; ++i) {
      e += x[i] * av[i];
      s += x[i] * x[i];
    }
    weight[k] = e > 0 ? s / e : 0.0;
    least = std::max(least, weight[k]);
  }
  for (double& w : weight) w = least > 0 ? w / least : 0.0;
  std::vector<int32_t> coarse_of(size_t(rows), -1);
  for (size_t c = 0; c < fine_row.size(); ++c) coarse_of[fine_row[c]] = int32_t(c);
  BlockMatrix& S = P.P;
#pragma omp parallel for schedule(static)
  for (int64_t f = 0; f < rows; ++f) {
    const int64_t b0 = S.start[f], k = S.start[f + 1] - b0;
    double* out = &S.val[9 * b0];
    if (coarse_of[f] >= 0 || k == 0) {
      for (int64_t b = 0; b < 9 * k; ++b) out[b] = 0.0;
      for (int64_t b = 0; b < k; ++b)
        if (S.col[b0 + b] == coarse_of[f]) out[9 * b] = out[9 * b + 4] = out[9 * b + 8] = 1.0;
      continue;
    }
    // P0's weights on this row's neighbours (zero where P0 has none).
    const int n = int(3 * k);
    double w0[kMaxNeighbours] = {};
    double rowsum = 0;
    for (int64_t q = P0.P.start[f]; q < P0.P.start[f + 1]; ++q)
      for (int64_t b = 0; b < k; ++b)
        if (S.col[b0 + b] == P0.P.col[q]) {
          w0[b] = P0.P.val[9 * q];
          rowsum += w0[b];
        }
    if (!full_blocks) {
      for (int i = 0; i < 3; ++i) fit_component(v, count, m, weight, fine_row, &S.col[b0], int(k), f, i, w0, rowsum,
                                                tikhonov, keep_sums, out);
      continue;
    }
    Gram G = Gram::Zero(n, n);
    Rhs R = Rhs::Zero(n, 3);
    double u[kMaxUnknowns];
    for (int t = 0; t < count; ++t) {
      const double* x = &v[size_t(t) * m];
      for (int64_t b = 0; b < k; ++b)
        for (int j = 0; j < 3; ++j) u[3 * b + j] = x[3 * fine_row[S.col[b0 + b]] + j];
      for (int a = 0; a < n; ++a) {
        for (int c = 0; c < n; ++c) G(a, c) += weight[t] * u[a] * u[c];
        for (int i = 0; i < 3; ++i) R(a, i) += weight[t] * u[a] * x[3 * f + i];
      }
    }
    double mu = 0;
    for (int a = 0; a < n; ++a) mu += G(a, a);
    mu = tikhonov * (mu > 0 ? mu / n : 1.0);
    for (int a = 0; a < n; ++a) {
      G(a, a) += mu;
      R(a, a % 3) += mu * w0[a / 3];  // the pull towards w0 I on each block
    }
    // min sum_t w_t |x_f - W u_t|^2 + mu |W - W0|^2 subject to the row sums
    // sum_b W_b = rowsum I: W^T = G^-1 (R - C^T L), C G^-1 C^T L = C G^-1 R - rowsum I,
    // C (3 x n) summing each component over the blocks.
    Eigen::LLT<Gram> llt(G);
    const Rhs GR = llt.solve(R);
    if (!keep_sums) {
      for (int64_t b = 0; b < k; ++b)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) out[9 * b + entry(i, j)] = GR(3 * b + j, i);
      continue;
    }
    Rhs Ct = Rhs::Zero(n, 3);
    for (int a = 0; a < n; ++a) Ct(a, a % 3) = 1.0;
    const Rhs GC = llt.solve(Ct);
    const Eigen::Matrix3d S3 = Ct.transpose() * GC;
    const Eigen::Matrix3d lam = S3.ldlt().solve(Ct.transpose() * GR - rowsum * Eigen::Matrix3d::Identity());
    const Rhs W = GR - GC * lam;  // W(3 b + j, i): row i, column j of block b
    for (int64_t b = 0; b < k; ++b)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) out[9 * b + entry(i, j)] = W(3 * b + j, i);
  }
  transpose(S, int64_t(fine_row.size()), P.T);
}

}  // namespace drape
