#include "solver/multigrid/coarse_solve.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace drape {

namespace {
inline bool has(const uint64_t* set, int64_t v) { return (set[v >> 6] >> (v & 63)) & 1u; }
inline void put(uint64_t* set, int64_t v) { set[v >> 6] |= uint64_t(1) << (v & 63); }
inline void drop(uint64_t* set, int64_t v) { set[v >> 6] &= ~(uint64_t(1) << (v & 63)); }
}  // namespace

// Minimum degree on the blocks' graph (3 unknowns eliminated together),
// with the fill made explicit in bit sets: the coarsest level holds about a
// hundred blocks, so whole rows of bits are cheap. Ties go to the lower
// block: the order follows from the pattern alone.
void CoarseSolve::order_blocks(const BlockMatrix& A) {
  const int64_t nb = A.rows, words = (nb + 63) / 64;
  resize_keeping(adj_, size_t(nb * words));
  resize_keeping(alive_, size_t(words));
  resize_keeping(degree_, size_t(nb));
  std::fill(adj_.begin(), adj_.end(), 0);
  std::fill(alive_.begin(), alive_.end(), 0);
  for (int64_t r = 0; r < nb; ++r) {
    put(alive_.data(), r);
    for (int64_t k = A.start[r]; k < A.start[r + 1]; ++k)
      if (A.col[k] != r) {
        put(&adj_[size_t(r * words)], A.col[k]);
        put(&adj_[size_t(int64_t(A.col[k]) * words)], r);
      }
  }
  auto degree = [&](int64_t u) {
    int64_t d = 0;
    for (int64_t w = 0; w < words; ++w) d += __builtin_popcountll(adj_[size_t(u * words + w)] & alive_[size_t(w)]);
    return d;
  };
  for (int64_t v = 0; v < nb; ++v) degree_[v] = degree(v);
  for (int64_t pos = 0; pos < nb; ++pos) {
    int64_t v = -1;
    for (int64_t u = 0; u < nb; ++u)
      if (has(alive_.data(), u) && (v < 0 || degree_[u] < degree_[v])) v = u;
    for (int c = 0; c < 3; ++c) perm_[size_t(3 * pos + c)] = 3 * v + c;
    drop(alive_.data(), v);
    const uint64_t* nv = &adj_[size_t(v * words)];
    // v's remaining neighbours become a clique.
    for (int64_t u = 0; u < nb; ++u) {
      if (!has(nv, u) || !has(alive_.data(), u)) continue;
      uint64_t* nu = &adj_[size_t(u * words)];
      for (int64_t w = 0; w < words; ++w) nu[w] |= nv[w] & alive_[size_t(w)];
      drop(nu, u);
      degree_[u] = degree(u);
    }
  }
}

// The permuted operator's upper triangle from A's lower one (diagonal
// included), each entry remembering its place in A.val.
void CoarseSolve::set_pattern(const BlockMatrix& A) {
  n_ = 3 * A.rows;
  const size_t n = size_t(n_);
  resize_keeping(perm_, n);
  resize_keeping(inv_, n);
  order_blocks(A);
  for (int64_t k = 0; k < n_; ++k) inv_[size_t(perm_[k])] = k;
  resize_keeping(ap_, n + 1);
  std::fill(ap_.begin(), ap_.end(), 0);
  auto each_lower = [&](auto&& f) {
    for (int64_t r = 0; r < A.rows; ++r)
      for (int64_t k = A.start[r]; k < A.start[r + 1]; ++k)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) {
            const int64_t row = 3 * r + i, col = 3 * int64_t(A.col[k]) + j;
            if (row < col) continue;
            const int64_t a = inv_[size_t(row)], b = inv_[size_t(col)];
            f(std::min(a, b), std::max(a, b), 9 * k + entry(i, j));
          }
  };
  each_lower([&](int64_t, int64_t c, int64_t) { ++ap_[size_t(c + 1)]; });
  for (size_t c = 0; c < n; ++c) ap_[c + 1] += ap_[c];
  resize_keeping(ai_, size_t(ap_[n]));
  resize_keeping(from_, size_t(ap_[n]));
  resize_keeping(ax_, size_t(ap_[n]));
  resize_keeping(lnz_, n);
  std::copy(ap_.begin(), ap_.end() - 1, lnz_.begin());  // each column's next free entry
  each_lower([&](int64_t r, int64_t c, int64_t at) {
    const int64_t q = lnz_[size_t(c)]++;
    ai_[size_t(q)] = r;
    from_[size_t(q)] = at;
  });
  symbolic();
}

// The elimination tree and L's column counts: row k of L reaches, from
// each entry i < k of column k, up the tree until a node already marked k.
void CoarseSolve::symbolic() {
  const size_t n = size_t(n_);
  resize_keeping(parent_, n);
  resize_keeping(flag_, n);
  resize_keeping(lp_, n + 1);
  for (int64_t k = 0; k < n_; ++k) {
    parent_[k] = -1;
    flag_[k] = k;
    lnz_[k] = 0;
    for (int64_t p = ap_[k]; p < ap_[k + 1]; ++p)
      for (int64_t i = ai_[p]; flag_[i] != k; i = parent_[i]) {
        if (parent_[i] < 0) parent_[i] = k;
        ++lnz_[i];
        flag_[i] = k;
      }
  }
  lp_[0] = 0;
  for (size_t k = 0; k < n; ++k) lp_[k + 1] = lp_[k] + lnz_[k];
  resize_keeping(li_, size_t(lp_[n]));
  resize_keeping(lx_, size_t(lp_[n]));
  resize_keeping(d_, n);
  resize_keeping(y_, n);
  resize_keeping(stack_, n);
}

// Up-looking LDL^T: row k of L from the triangular solve L D l = A(0:k, k),
// whose nonzeros are the tree paths found in symbolic(), taken in
// topological order (the stack's top first).
void CoarseSolve::factor(const BlockMatrix& A, bool pattern) {
  if (pattern) set_pattern(A);
  for (size_t p = 0, e = from_.size(); p < e; ++p) ax_[p] = A.val[size_t(from_[p])];
  std::fill(flag_.begin(), flag_.end(), -1);
  std::fill(y_.begin(), y_.end(), 0.0);
  int64_t* stack = stack_.data();
  for (int64_t k = 0; k < n_; ++k) {
    int64_t top = n_;
    flag_[k] = k;
    lnz_[k] = 0;
    for (int64_t p = ap_[k]; p < ap_[k + 1]; ++p) {
      int64_t i = ai_[p];
      y_[i] += ax_[p];
      int64_t len = 0;
      for (; flag_[i] != k; i = parent_[i]) {
        stack[len++] = i;
        flag_[i] = k;
      }
      while (len > 0) stack[--top] = stack[--len];
    }
    double dk = y_[k];
    y_[k] = 0;
    for (; top < n_; ++top) {
      const int64_t i = stack[top];
      const double yi = y_[i];
      y_[i] = 0;
      const int64_t end = lp_[i] + lnz_[i];
      for (int64_t p = lp_[i]; p < end; ++p) y_[li_[p]] -= lx_[p] * yi;
      const double lki = yi / d_[i];
      dk -= lki * yi;
      li_[end] = k;
      lx_[end] = lki;
      ++lnz_[i];
    }
    if (dk == 0 || !std::isfinite(dk)) throw std::runtime_error("multigrid: the coarsest level's factorisation failed");
    d_[k] = dk;
  }
}

void CoarseSolve::solve(const double* b, double* x) {
  double* w = y_.data();  // the factorisation's row, zeroed again when it next runs
  for (int64_t k = 0; k < n_; ++k) w[k] = b[perm_[k]];
  for (int64_t j = 0; j < n_; ++j)
    for (int64_t p = lp_[j]; p < lp_[j + 1]; ++p) w[li_[p]] -= lx_[p] * w[j];
  for (int64_t j = 0; j < n_; ++j) w[j] /= d_[j];
  for (int64_t j = n_ - 1; j >= 0; --j) {
    double s = w[j];
    for (int64_t p = lp_[j]; p < lp_[j + 1]; ++p) s -= lx_[p] * w[li_[p]];
    w[j] = s;
  }
  for (int64_t k = 0; k < n_; ++k) x[perm_[k]] = w[k];
}

}  // namespace drape
