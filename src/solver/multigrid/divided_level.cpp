#include "solver/multigrid/divided_level.hpp"

#include <omp.h>

#include <algorithm>
#include <stdexcept>

namespace drape {

namespace {
template <class T>
size_t bytes_of(const std::vector<T>& v) {
  return v.capacity() * sizeof(T);
}
}  // namespace

void DividedLevel::plan(const Reducer& red, const RankRows& rr, const BlockMatrix& mine, const BlockMatrix& all,
                        const Multigrid& mg) {
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
  // The ring: other ranks' rows in the restriction's rows here.
  std::vector<int64_t> ring;
  for (int64_t c : coarse_)
    for (int64_t k = T.start[c]; k < T.start[c + 1]; ++k)
      if (local[T.col[k]] < 0) ring.push_back(T.col[k]);
  std::sort(ring.begin(), ring.end());
  ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  // The ghosts: the ring, and other ranks' rows in K's rows here or the ring's.
  std::vector<int64_t> want = ring;
  for (int32_t g : mine.col)
    if (local[g] < 0) want.push_back(g);
  for (int64_t g : ring)
    for (int64_t k = all.start[g]; k < all.start[g + 1]; ++k)
      if (local[all.col[k]] < 0) want.push_back(all.col[k]);
  std::sort(want.begin(), want.end());
  want.erase(std::unique(want.begin(), want.end()), want.end());
  ghosts_ = want;
  for (size_t k = 0; k < ghosts_.size(); ++k) local[size_t(ghosts_[k])] = int32_t(own_ + int64_t(k));
  rows_ = global_;
  rows_.insert(rows_.end(), ghosts_.begin(), ghosts_.end());
  ring_.clear();
  ring_col_.clear();
  ring_start_.assign(1, 0);
  for (int64_t g : ring) {
    ring_.push_back(local[size_t(g)]);
    for (int64_t k = all.start[g]; k < all.start[g + 1]; ++k) ring_col_.push_back(local[size_t(all.col[k])]);
    ring_start_.push_back(int64_t(ring_col_.size()));
  }
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
  plan_messages(red, rr, local);
  const size_t nl = size_t(3 * (own_ + int64_t(ghosts_.size())));
  for (auto* v : {&x_, &res_, &bl_, &r_, &d_, &z_}) v->assign(nl, 0.0);
  for (auto* v : {&b1_, &x1_, &b1_cat_}) v->assign(size_t(3 * n1), 0.0);
  b1_mine_.assign(3 * coarse_.size(), 0.0);
  planned_ = mg.levels_built();
}

// Each rank asks each owner for its ghosts (ascending); the asks travel
// once, gathered, and each rank keeps the rows asked of it.
void DividedLevel::plan_messages(const Reducer& red, const RankRows& rr, const std::vector<int32_t>& local) {
  const int ranks = red.ranks(), me = red.rank();
  std::vector<int64_t> asks(size_t(ranks), 0);
  for (int64_t g : ghosts_) ++asks[size_t(rr.owner(g))];
  std::vector<int64_t> ask, scratch;
  recv_at_.clear();
  for (int k = 0; k < ranks; ++k)
    for (size_t i = 0; i < ghosts_.size(); ++i)
      if (rr.owner(ghosts_[i]) == k) {
        ask.push_back(ghosts_[i]);
        recv_at_.push_back(int32_t(own_ + int64_t(i)));
      }
  std::vector<int64_t> all_asks(size_t(ranks) * ranks), per_rank(size_t(ranks), ranks);
  gather_all(red, asks.data(), per_rank, all_asks.data(), scratch);
  int64_t total = 0;
  for (int q = 0; q < ranks; ++q) {
    per_rank[q] = 0;
    for (int k = 0; k < ranks; ++k) per_rank[q] += all_asks[size_t(q) * ranks + k];
    total += per_rank[q];
  }
  std::vector<int64_t> cat(static_cast<size_t>(total));
  gather_all(red, ask.data(), per_rank, cat.data(), scratch);
  send_at_.clear();
  send_bytes_.assign(size_t(ranks), 0);
  recv_bytes_.assign(size_t(ranks), 0);
  int64_t from = 0;
  for (int q = 0; q < ranks; ++q) {
    int64_t at = from;
    for (int k = 0; k < me; ++k) at += all_asks[size_t(q) * ranks + k];
    const int64_t n = all_asks[size_t(q) * ranks + me];
    for (int64_t i = 0; i < n; ++i) {
      const int32_t r = local[size_t(cat[at + i])];
      if (r < 0 || r >= own_) throw std::logic_error("DividedLevel: a rank asked for a row this rank does not own");
      send_at_.push_back(r);
    }
    send_bytes_[q] = 24 * n;
    recv_bytes_[q] = 24 * asks[q];
    from += per_rank[q];
  }
  sbuf_.assign(3 * send_at_.size(), 0.0);
  rbuf_.assign(3 * recv_at_.size(), 0.0);
}

void DividedLevel::exchange(const Reducer& red, double* v) {
  const size_t ns = send_at_.size(), nr = recv_at_.size();
  for (size_t i = 0; i < ns; ++i)
    for (int k = 0; k < 3; ++k) sbuf_[3 * i + k] = v[3 * int64_t(send_at_[i]) + k];
  red.exchange_bytes(sbuf_.data(), send_bytes_, rbuf_.data(), recv_bytes_);
  for (size_t i = 0; i < nr; ++i)
    for (int k = 0; k < 3; ++k) v[3 * int64_t(recv_at_[i]) + k] = rbuf_[3 * i + k];
  exchanged_ += 24 * int64_t(nr);
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

void DividedLevel::ring_residual(const BlockMatrix& all, const double* b, const double* x, double* r) const {
  const int64_t n = int64_t(ring_.size());
#pragma omp parallel for schedule(static)
  for (int64_t j = 0; j < n; ++j) {
    const int64_t i = ring_[j], g = rows_[i], s = all.start[g];
    double y[3];
    row_times(&all.val[9 * s], &ring_col_[size_t(ring_start_[j])], all.start[g + 1] - s, x, y);
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
      add_block_times(&M.val[9 * k], x1_.data() + 3 * int64_t(M.col[k]), 1.0, x + 3 * r);
  }
}

void DividedLevel::apply(const Reducer& red, const BlockMatrix& mine, const BlockMatrix& all, Multigrid& mg,
                         const double* b, double* s) {
  const double t0 = omp_get_wtime();
  if (mg.finest_smoother().degree() == 1) apply_one_step(red, mine, all, mg, b, s);
  else apply_steps(red, mine, mg, b, s);
  mg.count_finest(omp_get_wtime() - t0 - below_);
}

// The gathered cycle's steps (Multigrid::cycle at level 0), each on this
// rank's rows; the pre-smoothing step and the prolongation on the ghosts'
// rows too (as their owners do), so that the residuals read no message.
void DividedLevel::apply_one_step(const Reducer& red, const BlockMatrix& mine, const BlockMatrix& all, Multigrid& mg,
                                  const double* b, double* s) {
  const Chebyshev& ch = mg.finest_smoother();
  const Prolongation& P = mg.finest_transfer();
  const double* dinv = ch.dinv().data();
  auto dinv_row = [&](int64_t i) { return dinv + 9 * rows_[i]; };
  const int64_t nl = int64_t(rows_.size());
  double* x = x_.data();
  std::copy(b, b + 3 * own_, bl_.begin());
  exchange(red, bl_.data());
  auto none = [](double*, double*) {};  // from zero, one step: no product
  ch.smooth_rows(nl, bl_.data(), x, true, none, dinv_row, r_.data(), d_.data(), z_.data());
  own_residual(mine, b, x, res_.data());
  ring_residual(all, bl_.data(), x, res_.data());
  restrict_gather(red, P, res_.data());
  below(mg);
  prolong(P, nl, x);
  auto res = [&](double* y, double* r) { own_residual(mine, b, y, r); };
  ch.smooth_rows(own_, b, x, false, res, dinv_row, r_.data(), d_.data(), z_.data());
  std::copy(x, x + 3 * own_, s);
}

void DividedLevel::apply_steps(const Reducer& red, const BlockMatrix& mine, Multigrid& mg, const double* b,
                               double* s) {
  const Chebyshev& ch = mg.finest_smoother();
  const Prolongation& P = mg.finest_transfer();
  const double* dinv = ch.dinv().data();
  auto dinv_row = [&](int64_t i) { return dinv + 9 * rows_[i]; };
  auto res = [&](double* x, double* r) { residual(red, mine, b, x, r); };
  double* x = x_.data();
  ch.smooth_rows(own_, b, x, true, res, dinv_row, r_.data(), d_.data(), z_.data());
  residual(red, mine, b, x, res_.data());
  exchange(red, res_.data());
  restrict_gather(red, P, res_.data());
  below(mg);
  prolong(P, own_, x);
  ch.smooth_rows(own_, b, x, false, res, dinv_row, r_.data(), d_.data(), z_.data());
  std::copy(x, x + 3 * own_, s);
}

// Level 1 and below, whole (their seconds apart from the finest level's).
void DividedLevel::below(Multigrid& mg) {
  const double t0 = omp_get_wtime();
  mg.cycle_below(b1_.data(), x1_.data());
  below_ = omp_get_wtime() - t0;
}

size_t DividedLevel::memory() const {
  return bytes_of(global_) + bytes_of(ghosts_) + bytes_of(rows_) + bytes_of(ring_) + bytes_of(ring_col_) +
         bytes_of(ring_start_) + bytes_of(bl_) + bytes_of(kcol_) + bytes_of(coarse_) + bytes_of(tcol_) +
         bytes_of(tstart_) + bytes_of(coarse_of_) + bytes_of(coarse_rows_) + bytes_of(gather_counts_) +
         bytes_of(send_at_) + bytes_of(recv_at_) + bytes_of(send_bytes_) + bytes_of(recv_bytes_) +
         bytes_of(gather_bytes_) + bytes_of(sbuf_) + bytes_of(rbuf_) + bytes_of(x_) + bytes_of(res_) + bytes_of(r_) +
         bytes_of(d_) + bytes_of(z_) + bytes_of(b1_) + bytes_of(x1_) + bytes_of(b1_mine_) + bytes_of(b1_cat_);
}

}  // namespace drape
