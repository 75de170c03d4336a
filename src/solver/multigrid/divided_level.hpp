#pragma once
// The multigrid's finest level on several ranks, divided: each rank runs
// the finest level's part of the V-cycle (the Chebyshev sweeps' products,
// the residual, its restriction to level 1's points) on its own rows of K,
// with the few entries of other ranks' rows that they read exchanged (with
// degree 1, the right-hand side's once a cycle, the ghosts' steps repeated
// here); only
// the restricted residual is gathered (level 1 and below run whole on every
// rank, as RankRows' gathered levels), and each rank prolongs level 1's
// correction onto its own rows. Every row's sums are the gathered cycle's,
// in the same order (row_times, Chebyshev::smooth_rows): the same result,
// bit for bit, as Multigrid::apply on the gathered K.
//
// Still whole on every rank: the levels' build (K gathered, level 1's
// Galerkin product, the smoother's inverse blocks and spectrum estimate)
// and level 1 and below.
//
// A rank's vectors: its rows in its own order (RankRows::mine), then the
// other ranks' rows its rows and its restriction read, and those that the
// restriction's rows read (its ghosts), ascending by global row.
#include <cstdint>
#include <vector>

#include "solver/multigrid/block_matrix.hpp"
#include "solver/multigrid/multigrid.hpp"
#include "solver/multigrid/rank_rows.hpp"
#include "solver/reducer.hpp"

namespace drape {

class DividedLevel {
 public:
  // The ghosts, columns and messages for this rank's rows `mine` of K
  // (global columns, rr's numbering) and mg's levels (built on every
  // rank's rows). Collective.
  // `all`: every rank's rows (the levels' finest), read for the rows next
  // to this rank's whose residual its restriction reads.
  void plan(const Reducer& red, const RankRows& rr, const BlockMatrix& mine, const BlockMatrix& all,
            const Multigrid& mg);
  // Whether plan() followed mg's present levels.
  bool planned(const Multigrid& mg) const { return planned_ == mg.levels_built() && planned_ != 0; }
  // s = M^-1 r, one V-cycle from zero, on this rank's rows (3 doubles a
  // row of `mine`, its order): `mine` and mg as planned, with the values of
  // the last build. Collective.
  void apply(const Reducer& red, const BlockMatrix& mine, const BlockMatrix& all, Multigrid& mg, const double* r,
             double* s);
  // Bytes this rank receives: gathered in a cycle (level 1's right-hand
  // side), exchanged in all cycles so far (its ghosts' entries).
  int64_t gathered_bytes() const { return 24 * int64_t(coarse_of_.size()); }
  int64_t exchanged_bytes() const { return exchanged_; }
  int64_t ghosts() const { return int64_t(ghosts_.size()); }
  size_t memory() const;

 private:
  void plan_messages(const Reducer& red, const RankRows& rr, const std::vector<int32_t>& local);
  // Chebyshev of degree 1 (one step from zero before and after): every
  // entry the cycle reads follows from the right-hand side's entries there,
  // so it is exchanged once and the ghosts' steps are repeated here; with
  // the gather, two rounds of messages a cycle. Other degrees exchange
  // before each product.
  void apply_one_step(const Reducer& red, const BlockMatrix& mine, const BlockMatrix& all, Multigrid& mg,
                      const double* b, double* s);
  void apply_steps(const Reducer& red, const BlockMatrix& mine, Multigrid& mg, const double* b, double* s);
  // The residual at the ring's rows (rows of `all`, x whole there).
  void ring_residual(const BlockMatrix& all, const double* b, const double* x, double* r) const;
  // v's ghost entries from their owners (v: 3 a row, this rank's layout).
  void exchange(const Reducer& red, double* v);
  // r = b - A x on this rank's rows, x's ghost entries exchanged first (or as they are).
  void residual(const Reducer& red, const BlockMatrix& mine, const double* b, double* x, double* r);
  void own_residual(const BlockMatrix& mine, const double* b, const double* x, double* r) const;
  void below(Multigrid& mg);
  // Level 1's right-hand side, whole: this rank's points restricted from
  // its residual, every rank's gathered.
  void restrict_gather(const Reducer& red, const Prolongation& P, const double* res);
  // x += P x1 on this rank's rows.
  void prolong(const Prolongation& P, int64_t rows, double* x) const;

  uint64_t planned_ = 0;
  int64_t own_ = 0;
  std::vector<int64_t> global_;       // this rank's row -> its global row
  std::vector<int64_t> ghosts_;       // global rows, ascending
  std::vector<int64_t> rows_;         // this rank's layout -> global row (its rows, then the ghosts)
  // The ring: other ranks' rows whose residual the restriction reads (their
  // place in this rank's layout), and their blocks' columns in it.
  std::vector<int32_t> ring_;
  std::vector<int32_t> ring_col_;
  std::vector<int64_t> ring_start_;
  std::vector<int32_t> kcol_;         // K's blocks' columns in this rank's layout
  std::vector<int64_t> coarse_;       // level-1 points this rank restricts to (ascending)
  std::vector<int32_t> tcol_;         // their restriction rows' columns, this rank's layout
  std::vector<int64_t> tstart_;       // where each of them starts in tcol_
  std::vector<int64_t> coarse_of_;    // level-1 point -> its place in the ranks' concatenation
  std::vector<int64_t> coarse_rows_;  // level-1 points per rank
  std::vector<int64_t> gather_counts_;  // their values per rank (3 each)
  // Messages: the rows sent (this rank's) and received (ghosts' places),
  // rank after rank, and their bytes per rank.
  std::vector<int32_t> send_at_, recv_at_;
  std::vector<int64_t> send_bytes_, recv_bytes_, gather_bytes_;
  std::vector<double> sbuf_, rbuf_;
  // This rank's vectors: x and the residual (rows and ghosts), the
  // smoother's workspaces (rows), level 1's whole right-hand side and
  // correction, this rank's part of it and the concatenation.
  std::vector<double> x_, res_, r_, d_, z_, b1_, x1_, b1_mine_, b1_cat_, bl_;
  int64_t exchanged_ = 0;
  double below_ = 0;  // the last cycle's seconds in level 1 and below
};

}  // namespace drape
