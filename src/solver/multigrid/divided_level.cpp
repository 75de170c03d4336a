#include "solver/multigrid/divided_level.hpp"

#include "solver/multigrid/block_product.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace drape {

namespace {
template <class T>
size_t bytes_of(const std::vector<T>& v) {
  return v.capacity() * sizeof(T);
}
}  // namespace

void DividedLevel::plan(const Reducer& red, const RankRows& rr, const BlockMatrix& mine, const Multigrid& mg) {
  if (!mg.finest_by_points()) throw std::logic_error("DividedLevel: the finest level is not smoothed by points");
  const int ranks = red.ranks(), me = red.rank();
  const BlockMatrix& T = mg.finest_transfer().T;
  global_ = rr.mine();
  own_ = mine.rows;
  // Global row -> this rank's layout (its rows first; ghosts below).
  std::vector<int32_t> local(size_t(rr.size()), -1);
  for (int64_t r = 0; r < own_; ++r) local[size_t(global_[r])] = int32_t(r);
  // Level 1's points belong to the rank of their finest row.
  const std::vector<int64_t>& points = mg.level_ids(1);
  const int64_t n1 = int64_t(points.size());
  std::vector<int> owner(static_cast<size_t>(n1));
  coarse_.clear();
  coarse_rows_.assign(size_t(ranks), 0);
  for (int64_t c = 0; c < n1; ++c) {
    owner[c] = rr.owner(rr.column_of()[size_t(points[c])]);
    ++coarse_rows_[size_t(owner[c])];
    if (owner[c] == me) coarse_.push_back(c);
  }
  // The ring: other ranks' rows in the restriction's rows here, asked of
  // their owners (their rows of K arrive in the order asked).
  std::vector<int64_t> ring;
  for (int64_t c : coarse_)
    for (int64_t k = T.start[c]; k < T.start[c + 1]; ++k)
      if (local[T.col[k]] < 0) ring.push_back(T.col[k]);
  std::sort(ring.begin(), ring.end());
  ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  plan_asks(red, rr, local, ring, ring_asks_);
  fetch_ring(red, mine, true);
  // The ghosts: the ring, and other ranks' rows in K's rows here or the ring's.
  std::vector<int64_t> want = ring;
  for (int32_t g : mine.col)
    if (local[g] < 0) want.push_back(g);
  for (int32_t g : ring_k_.col)
    if (local[g] < 0) want.push_back(g);
  std::sort(want.begin(), want.end());
  want.erase(std::unique(want.begin(), want.end()), want.end());
  ghosts_ = want;
  for (size_t k = 0; k < ghosts_.size(); ++k) local[size_t(ghosts_[k])] = int32_t(own_ + int64_t(k));
  rows_ = global_;
  rows_.insert(rows_.end(), ghosts_.begin(), ghosts_.end());
  ring_.clear();
  ring_of_.assign(ghosts_.size(), -1);
  for (int64_t g : ring_asks_.recv) {
    ring_of_[size_t(local[size_t(g)] - own_)] = int32_t(ring_.size());
    ring_.push_back(local[size_t(g)]);
  }
  ring_col_.resize(ring_k_.col.size());
  for (size_t b = 0; b < ring_k_.col.size(); ++b) ring_col_[b] = local[size_t(ring_k_.col[b])];
  kcol_.resize(mine.col.size());
  for (size_t b = 0; b < mine.col.size(); ++b) kcol_[b] = local[size_t(mine.col[b])];
  tstart_.assign(1, 0);
  tcol_.clear();
  for (int64_t c : coarse_) {
    for (int64_t k = T.start[c]; k < T.start[c + 1]; ++k) tcol_.push_back(local[T.col[k]]);
    tstart_.push_back(int64_t(tcol_.size()));
  }
  // Level 1's points in the ranks' concatenation: rank after rank, each
  // rank's ascending.
  std::vector<int64_t> at(size_t(ranks), 0);
  for (int k = 1; k < ranks; ++k) at[k] = at[k - 1] + coarse_rows_[k - 1];
  coarse_of_.resize(size_t(n1));
  for (int64_t c = 0; c < n1; ++c) coarse_of_[c] = at[size_t(owner[c])]++;
  gather_counts_.resize(size_t(ranks));
  for (int k = 0; k < ranks; ++k) gather_counts_[k] = 3 * coarse_rows_[k];
  plan_asks(red, rr, local, ghosts_, ghost_asks_);
  recv_at_.clear();  // the ghosts arrive owner after owner
  for (int64_t g : ghost_asks_.recv) recv_at_.push_back(local[size_t(g)]);
  send_bytes_.resize(size_t(ranks));
  recv_bytes_.resize(size_t(ranks));
  for (int k = 0; k < ranks; ++k) {
    send_bytes_[k] = 24 * ghost_asks_.send_rows[k];
    recv_bytes_[k] = 24 * ghost_asks_.recv_rows[k];
  }
  sbuf_.assign(9 * ghost_asks_.send_at.size(), 0.0);
  rbuf_.assign(9 * ghosts_.size(), 0.0);
  const size_t nl = size_t(3 * (own_ + int64_t(ghosts_.size())));
  for (auto* v : {&x_, &res_, &bl_, &r_, &d_, &z_}) v->assign(nl, 0.0);
  dinv_.assign(3 * nl, 0.0);
  for (auto* v : {&b1_, &x1_, &b1_cat_}) v->assign(size_t(3 * n1), 0.0);
  b1_mine_.assign(3 * coarse_.size(), 0.0);
  planned_ = mg.levels_built();
  patterned_ = false;
}

// Each rank tells each owner how many rows it asks, then the rows (all
// asks gathered, few); each rank keeps the rows asked of it.
void DividedLevel::plan_asks(const Reducer& red, const RankRows& rr, const std::vector<int32_t>& local,
                             const std::vector<int64_t>& want, Asks& a) {
  const int ranks = red.ranks(), me = red.rank();
  a.recv_rows.assign(size_t(ranks), 0);
  for (int64_t g : want) ++a.recv_rows[size_t(rr.owner(g))];
  std::vector<int64_t> scratch;
  a.recv.clear();
  for (int k = 0; k < ranks; ++k)
    for (int64_t g : want)
      if (rr.owner(g) == k) a.recv.push_back(g);
  std::vector<int64_t> all_asks(size_t(ranks) * ranks), per_rank(size_t(ranks), ranks);
  gather_all(red, a.recv_rows.data(), per_rank, all_asks.data(), scratch);
  int64_t total = 0;
  for (int q = 0; q < ranks; ++q) {
    per_rank[q] = 0;
    for (int k = 0; k < ranks; ++k) per_rank[q] += all_asks[size_t(q) * ranks + k];
    total += per_rank[q];
  }
  std::vector<int64_t> cat(static_cast<size_t>(total));
  gather_all(red, a.recv.data(), per_rank, cat.data(), scratch);
  a.send_at.clear();
  a.send_rows.assign(size_t(ranks), 0);
  int64_t from = 0;
  for (int q = 0; q < ranks; ++q) {
    int64_t at = from;
    for (int k = 0; k < me; ++k) at += all_asks[size_t(q) * ranks + k];
    const int64_t n = all_asks[size_t(q) * ranks + me];
    for (int64_t i = 0; i < n; ++i) {
      const int32_t r = local[size_t(cat[at + i])];
      if (r < 0 || r >= own_) throw std::logic_error("DividedLevel: a rank asked for a row this rank does not own");
      a.send_at.push_back(r);
    }
    a.send_rows[q] = n;
    from += per_rank[q];
  }
}

// The ring's rows' lengths and columns (pattern), or their values, from
// their owners: each owner sends the rows asked of it whole, in the order asked.
void DividedLevel::fetch_ring(const Reducer& red, const BlockMatrix& mine, bool pattern) {
  const Asks& a = ring_asks_;
  const int ranks = int(a.send_rows.size());
  std::vector<int64_t> sb(static_cast<size_t>(ranks)), rb(static_cast<size_t>(ranks));
  if (pattern) {
    std::vector<int64_t> len(a.send_at.size()), got(a.recv.size());
    for (size_t i = 0; i < a.send_at.size(); ++i) len[i] = mine.start[a.send_at[i] + 1] - mine.start[a.send_at[i]];
    for (int k = 0; k < ranks; ++k) {
      sb[k] = 8 * a.send_rows[k];
      rb[k] = 8 * a.recv_rows[k];
    }
    red.exchange_bytes(len.data(), sb, got.data(), rb);
    ring_k_.rows = int64_t(got.size());
    ring_k_.start.assign(got.size() + 1, 0);
    for (size_t i = 0; i < got.size(); ++i) ring_k_.start[i + 1] = ring_k_.start[i] + got[i];
    ring_k_.col.resize(size_t(ring_k_.blocks()));
    ring_k_.val.resize(9 * ring_k_.col.size());
    ring_send_blocks_.assign(size_t(ranks), 0);
    size_t i = 0;
    for (int k = 0; k < ranks; ++k)
      for (int64_t n = 0; n < a.send_rows[k]; ++n, ++i) ring_send_blocks_[k] += len[i];
  }
  std::vector<int64_t> recv_blocks(size_t(ranks), 0);
  for (int k = 0, i = 0; k < ranks; ++k)
    for (int64_t n = 0; n < a.recv_rows[k]; ++n, ++i)
      recv_blocks[k] += ring_k_.start[i + 1] - ring_k_.start[i];
  const int64_t bytes = pattern ? 4 : 72;  // a block's column, or its values
  int64_t sent = 0;
  for (int k = 0; k < ranks; ++k) {
    sb[k] = bytes * ring_send_blocks_[k];
    rb[k] = bytes * recv_blocks[k];
    sent += ring_send_blocks_[k];
  }
  if (pattern) {
    std::vector<int32_t> out(static_cast<size_t>(sent));
    size_t o = 0;
    for (int32_t r : a.send_at)
      for (int64_t b = mine.start[r]; b < mine.start[r + 1]; ++b) out[o++] = mine.col[b];
    red.exchange_bytes(out.data(), sb, ring_k_.col.data(), rb);
  } else {
    std::vector<double> out(static_cast<size_t>(9 * sent));
    size_t o = 0;
    for (int32_t r : a.send_at)
      for (int64_t b = 9 * mine.start[r]; b < 9 * mine.start[r + 1]; ++b) out[o++] = mine.val[b];
    red.exchange_bytes(out.data(), sb, ring_k_.val.data(), rb);
  }
  for (int64_t b : rb) exchanged_ += b;
}

void DividedLevel::build(const Reducer& red, RankRows& rr, const BlockMatrix& mine, Multigrid& mg, bool whole,
                         bool fresh) {
  fetch_ring(red, mine, false);
  finest_smoother(red, mine, mg, whole, fresh);
  build_bytes_ = 0;
  if (whole) return;
  power_iteration(red, rr, mine, mg.settings(), fresh);
  level_one(mine, mg, fresh || !patterned_);
  patterned_ = true;
  build_bytes_ += gather_rows(red, a1_mine_, coarse_rows_, coarse_of_, mg.level_one());
  mg.setup_below(fresh, red.sum_i64(mine.blocks()));
}

// The layout's inverse diagonal blocks: this rank's rows' inverted here
// (or copied from the whole levels'), the ghosts' from their owners.
void DividedLevel::finest_smoother(const Reducer& red, const BlockMatrix& mine, const Multigrid& mg, bool whole,
                                   bool fresh) {
  if (whole) {
    ch_ = &mg.finest_smoother();
    const double* all = ch_->dinv().data();
    const int64_t nl = int64_t(rows_.size());
    for (int64_t i = 0; i < nl; ++i) std::copy(all + 9 * rows_[i], all + 9 * rows_[i] + 9, &dinv_[9 * i]);
    return;
  }
  if (fresh) forget();
  int64_t bad = 0;
#pragma omp parallel for schedule(static) reduction(+ : bad)
  for (int64_t i = 0; i < own_; ++i) {
    const double* a = mine.block(i, int32_t(global_[i]));
    bad += !(a && invert_stored_block(a, &dinv_[9 * i]));
  }
  if (red.sum_i64(bad) > 0) throw std::runtime_error("multigrid: a particle's diagonal block is singular");
  exchange(red, dinv_.data(), 9);
  ch_ = &cheb_;
}

// Chebyshev::setup's power iteration on D^-1 K, on this rank's rows: the
// same steps, each product's ghost entries exchanged, each norm over the
// vector gathered whole (one rank's order of the sum).
void DividedLevel::power_iteration(const Reducer& red, RankRows& rr, const BlockMatrix& mine,
                                   const MultigridSettings& ms, bool fresh) {
  int steps = Chebyshev::warm_steps;
  if (fresh || eig_.size() != size_t(3 * own_)) {
    eig_.resize(size_t(3 * own_));
    for (int64_t r = 0; r < own_; ++r)
      for (int k = 0; k < 3; ++k) eig_[3 * r + k] = Chebyshev::start_entry(3 * global_[r] + k);
    steps = Chebyshev::cold_steps;
  }
  eig_all_.resize(size_t(3 * rr.size()));
  auto gathered_norm2 = [&]() {
    rr.gather(red, eig_.data(), eig_all_.data());
    build_bytes_ += rr.vector_bytes();
    return ordered_norm2(eig_all_);
  };
  double lam = 1, n2 = gathered_norm2();
  double* x = x_.data();
  for (int it = 0; it < steps; ++it) {
    const double nd = std::sqrt(n2);
    if (!(nd > 0)) break;
    for (int64_t i = 0; i < 3 * own_; ++i) x[i] = eig_[i] /= nd;
    exchange(red, x);
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < own_; ++i) {
      const int64_t s = mine.start[i];
      double y[3];
      row_times(&mine.val[9 * s], &kcol_[size_t(s)], mine.start[i + 1] - s, x, y);
      const double* m = &dinv_[9 * i];
      for (int k = 0; k < 3; ++k) eig_[3 * i + k] = m[3 * k] * y[0] + m[3 * k + 1] * y[1] + m[3 * k + 2] * y[2];
    }
    n2 = gathered_norm2();
    lam = std::sqrt(n2);
  }
  cheb_.set_spectrum(ms.degree, ms.ratio, lam);
}

// Level 1's rows of this rank's points, as galerkin() sums them: K P on
// the fine rows held (block_product's rows), then T's rows times those.
void DividedLevel::level_one(const BlockMatrix& mine, const Multigrid& mg, bool pattern) {
  const Prolongation& P = mg.finest_transfer();
  const BlockMatrix& T = P.T;
  const int64_t nc = P.coarse();
  auto times_p = P.scalar ? block_product_scalar_right : block_product;
  times_p(mine, P.P, nc, ap_own_, pattern);
  times_p(ring_k_, P.P, nc, ap_ring_, pattern);
  // Fine row of the layout -> its row of K P (this rank's, or the ring's).
  auto ap = [&](int32_t i, int64_t& row) -> const BlockMatrix& {
    if (i < own_) {
      row = i;
      return ap_own_;
    }
    row = ring_of_[size_t(i - own_)];
    return ap_ring_;
  };
  const int64_t mc = int64_t(coarse_.size());
  if (pattern)
    build_pattern(a1_mine_, mc, pattern_, [&](int64_t j, auto&& push) {
      for (int64_t k = tstart_[j]; k < tstart_[j + 1]; ++k) {
        int64_t row;
        const BlockMatrix& M = ap(tcol_[k], row);
        for (int64_t b = M.start[row]; b < M.start[row + 1]; ++b) push(M.col[b]);
      }
    });
  slots_.size(omp_get_max_threads(), nc);
#pragma omp parallel
  {
    std::vector<int64_t>& slot = slots_.of[size_t(omp_get_thread_num())];
#pragma omp for schedule(static)
    for (int64_t j = 0; j < mc; ++j) {
      const int64_t c = coarse_[j];
      for (int64_t k = a1_mine_.start[j]; k < a1_mine_.start[j + 1]; ++k) slot[a1_mine_.col[k]] = k;
      std::fill(a1_mine_.val.begin() + 9 * a1_mine_.start[j], a1_mine_.val.begin() + 9 * a1_mine_.start[j + 1], 0.0);
      for (int64_t k = tstart_[j]; k < tstart_[j + 1]; ++k) {
        const double* t = &T.val[9 * (T.start[c] + k - tstart_[j])];
        int64_t row;
        const BlockMatrix& M = ap(tcol_[k], row);
        if (P.scalar)  // t = w I: the same sums, w read alone
          for (int64_t b = M.start[row]; b < M.start[row + 1]; ++b)
            add_scaled_block(t[0], &M.val[9 * b], &a1_mine_.val[9 * slot[M.col[b]]]);
        else
          for (int64_t b = M.start[row]; b < M.start[row + 1]; ++b)
            add_block_product(t, &M.val[9 * b], &a1_mine_.val[9 * slot[M.col[b]]]);
      }
      for (int64_t k = a1_mine_.start[j]; k < a1_mine_.start[j + 1]; ++k) slot[a1_mine_.col[k]] = -1;
    }
  }
}

void DividedLevel::exchange(const Reducer& red, double* v, int width) {
  const std::vector<int32_t>& send_at = ghost_asks_.send_at;
  const size_t ns = send_at.size(), nr = ghosts_.size();
  const int64_t w = width;
  for (size_t i = 0; i < ns; ++i)
    for (int64_t k = 0; k < w; ++k) sbuf_[w * i + k] = v[w * int64_t(send_at[i]) + k];
  if (width == 3) {
    red.exchange_bytes(sbuf_.data(), send_bytes_, rbuf_.data(), recv_bytes_);
  } else {
    wide_send_.resize(send_bytes_.size());
    wide_recv_.resize(recv_bytes_.size());
    for (size_t k = 0; k < send_bytes_.size(); ++k) {
      wide_send_[k] = send_bytes_[k] / 3 * width;
      wide_recv_[k] = recv_bytes_[k] / 3 * width;
    }
    red.exchange_bytes(sbuf_.data(), wide_send_, rbuf_.data(), wide_recv_);
  }
  for (size_t i = 0; i < nr; ++i)
    for (int64_t k = 0; k < w; ++k) v[w * int64_t(recv_at_[i]) + k] = rbuf_[w * i + k];
  exchanged_ += 8 * w * int64_t(nr);
}

void DividedLevel::residual(const Reducer& red, const BlockMatrix& mine, const double* b, double* x, double* r) {
  exchange(red, x);
  own_residual(mine, b, x, r);
}

void DividedLevel::own_residual(const BlockMatrix& mine, const double* b, const double* x, double* r) const {
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < own_; ++i) {
    const int64_t s = mine.start[i];
    double y[3];
    row_times(&mine.val[9 * s], &kcol_[size_t(s)], mine.start[i + 1] - s, x, y);
    for (int k = 0; k < 3; ++k) r[3 * i + k] = b[3 * i + k] - y[k];
  }
}

void DividedLevel::ring_residual(const double* b, const double* x, double* r) const {
  const int64_t n = int64_t(ring_.size());
#pragma omp parallel for schedule(static)
  for (int64_t j = 0; j < n; ++j) {
    const int64_t i = ring_[j], s = ring_k_.start[j];
    double y[3];
    row_times(&ring_k_.val[9 * s], &ring_col_[size_t(s)], ring_k_.start[j + 1] - s, x, y);
    for (int k = 0; k < 3; ++k) r[3 * i + k] = b[3 * i + k] - y[k];
  }
}

void DividedLevel::restrict_gather(const Reducer& red, const Prolongation& P, const double* res) {
  const BlockMatrix& T = P.T;
  const int64_t mc = int64_t(coarse_.size());
#pragma omp parallel for schedule(static)
  for (int64_t j = 0; j < mc; ++j) {
    const int64_t c = coarse_[j];
    row_times(&T.val[9 * T.start[c]], &tcol_[size_t(tstart_[j])], T.start[c + 1] - T.start[c], res, &b1_mine_[3 * j]);
  }
  gather_all(red, b1_mine_.data(), gather_counts_, b1_cat_.data(), gather_bytes_);
  const int64_t n1 = int64_t(coarse_of_.size());
#pragma omp parallel for schedule(static)
  for (int64_t c = 0; c < n1; ++c)
    for (int k = 0; k < 3; ++k) b1_[3 * c + k] = b1_cat_[3 * coarse_of_[c] + k];
}

void DividedLevel::prolong(const Prolongation& P, int64_t rows, double* x) const {
  const BlockMatrix& M = P.P;
#pragma omp parallel for schedule(static)
  for (int64_t r = 0; r < rows; ++r) {
    const int64_t f = rows_[r];
    for (int64_t k = M.start[f]; k < M.start[f + 1]; ++k)
      add_stored_block_times(&M.val[9 * k], x1_.data() + 3 * int64_t(M.col[k]), x + 3 * r);
  }
}

void DividedLevel::apply(const Reducer& red, const BlockMatrix& mine, Multigrid& mg, const double* b, double* s) {
  const double t0 = omp_get_wtime();
  if (ch_->degree() == 1) apply_one_step(red, mine, mg, b, s);
  else apply_steps(red, mine, mg, b, s);
  mg.count_finest(omp_get_wtime() - t0 - below_);
}

// The gathered cycle's steps (Multigrid::cycle at level 0), each on this
// rank's rows; the pre-smoothing step and the prolongation on the ghosts'
// rows too (as their owners do), so that the residuals read no message.
void DividedLevel::apply_one_step(const Reducer& red, const BlockMatrix& mine, Multigrid& mg, const double* b,
                                  double* s) {
  const Prolongation& P = mg.finest_transfer();
  auto dinv_row = [&](int64_t i) { return &dinv_[9 * i]; };
  const int64_t nl = int64_t(rows_.size());
  double* x = x_.data();
  std::copy(b, b + 3 * own_, bl_.begin());
  exchange(red, bl_.data());
  auto none = [](double*, double*) {};  // from zero, one step: no product
  ch_->smooth_rows(nl, bl_.data(), x, true, none, dinv_row, r_.data(), d_.data(), z_.data());
  own_residual(mine, b, x, res_.data());
  ring_residual(bl_.data(), x, res_.data());
  restrict_gather(red, P, res_.data());
  below(mg);
  prolong(P, nl, x);
  auto res = [&](double* y, double* r) { own_residual(mine, b, y, r); };
  ch_->smooth_rows(own_, b, x, false, res, dinv_row, r_.data(), d_.data(), z_.data());
  std::copy(x, x + 3 * own_, s);
}

void DividedLevel::apply_steps(const Reducer& red, const BlockMatrix& mine, Multigrid& mg, const double* b,
                               double* s) {
  const Prolongation& P = mg.finest_transfer();
  auto dinv_row = [&](int64_t i) { return &dinv_[9 * i]; };
  auto res = [&](double* x, double* r) { residual(red, mine, b, x, r); };
  double* x = x_.data();
  ch_->smooth_rows(own_, b, x, true, res, dinv_row, r_.data(), d_.data(), z_.data());
  residual(red, mine, b, x, res_.data());
  exchange(red, res_.data());
  restrict_gather(red, P, res_.data());
  below(mg);
  prolong(P, own_, x);
  ch_->smooth_rows(own_, b, x, false, res, dinv_row, r_.data(), d_.data(), z_.data());
  std::copy(x, x + 3 * own_, s);
}

// Level 1 and below, whole (their seconds apart from the finest level's).
void DividedLevel::below(Multigrid& mg) {
  const double t0 = omp_get_wtime();
  mg.cycle_below(b1_.data(), x1_.data());
  below_ = omp_get_wtime() - t0;
}

size_t DividedLevel::memory() const {
  auto matrix = [](const BlockMatrix& m) { return bytes_of(m.start) + bytes_of(m.col) + bytes_of(m.val); };
  auto asks = [](const Asks& a) {
    return bytes_of(a.recv) + bytes_of(a.send_at) + bytes_of(a.send_rows) + bytes_of(a.recv_rows);
  };
  return bytes_of(global_) + bytes_of(ghosts_) + bytes_of(rows_) + bytes_of(ring_) + matrix(ring_k_) +
         bytes_of(ring_col_) + bytes_of(ring_of_) + asks(ring_asks_) + asks(ghost_asks_) +
         bytes_of(ring_send_blocks_) + bytes_of(recv_at_) + bytes_of(bl_) + bytes_of(kcol_) + bytes_of(coarse_) +
         bytes_of(tcol_) + bytes_of(tstart_) + bytes_of(coarse_of_) + bytes_of(coarse_rows_) +
         bytes_of(gather_counts_) + bytes_of(send_bytes_) + bytes_of(recv_bytes_) + bytes_of(gather_bytes_) +
         bytes_of(wide_send_) + bytes_of(wide_recv_) + bytes_of(sbuf_) + bytes_of(rbuf_) + bytes_of(dinv_) +
         bytes_of(eig_) + bytes_of(eig_all_) + matrix(ap_own_) + matrix(ap_ring_) + matrix(a1_mine_) +
         bytes_of(pattern_.at) + bytes_of(pattern_.col) + bytes_of(pattern_.kept) + bytes_of(x_) + bytes_of(res_) +
         bytes_of(r_) + bytes_of(d_) + bytes_of(z_) + bytes_of(b1_) + bytes_of(x1_) + bytes_of(b1_mine_) +
         bytes_of(b1_cat_);
}

}  // namespace drape
