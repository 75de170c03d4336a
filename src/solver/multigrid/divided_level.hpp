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
// Its build needs no rank to hold K whole where the finest transfer is the
// bilinear P (Multigrid::finest_divisible): each rank keeps its own rows of
// K and the ring's (other ranks' rows that its level-1 points' restriction
// reads, received from their owners), inverts its own diagonal blocks, runs
// the power iteration for the smoother's lambda max on its own rows (the
// vector gathered at each step, so that its norm sums in the one-rank
// order), and computes its level-1 points' rows of R K P in the one-rank
// order; only those rows are gathered, and level 1 and below are built
// whole on every rank. Else (a smoothed or fitted finest P) the levels are
// built on K gathered and this class copies the finest smoother's blocks.
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
  // (global columns, rr's numbering) and mg's points and transfers; the
  // ring's rows' patterns from their owners. Collective.
  void plan(const Reducer& red, const RankRows& rr, const BlockMatrix& mine, const Multigrid& mg);
  // Whether plan() followed mg's present levels.
  bool planned(const Multigrid& mg) const { return planned_ == mg.levels_built() && planned_ != 0; }
  // After each assembly of `mine` (planned): the ring's values and the
  // finest smoother. `whole`: mg was set up on K gathered (its finest
  // smoother's blocks are copied); else the smoother and level 1's operator
  // are built here from the rows held, and mg's levels below (setup_below).
  // `fresh`: K's pattern is new (Multigrid::setup_points). Collective.
  void build(const Reducer& red, RankRows& rr, const BlockMatrix& mine, Multigrid& mg, bool whole, bool fresh);
  // The next build's power iteration starts cold (Multigrid::forget).
  void forget() { eig_.clear(); }
  // s = M^-1 r, one V-cycle from zero, on this rank's rows (3 doubles a
  // row of `mine`, its order): `mine` and mg as built. Collective.
  void apply(const Reducer& red, const BlockMatrix& mine, Multigrid& mg, const double* r, double* s);
  // Bytes this rank receives: gathered in a cycle (level 1's right-hand
  // side), gathered in the last build (level 1's rows and the power
  // iteration's vectors; 0 where the levels were built on K gathered),
  // exchanged in all builds and cycles so far (its ghosts' entries, the ring's rows).
  int64_t gathered_bytes() const { return 24 * int64_t(coarse_of_.size()); }
  int64_t build_bytes() const { return build_bytes_; }
  int64_t exchanged_bytes() const { return exchanged_; }
  int64_t ghosts() const { return int64_t(ghosts_.size()); }
  int64_t ring_rows() const { return ring_k_.rows; }
  // This rank's rows of level 1's operator (its level-1 points, ascending).
  const BlockMatrix& level_one_rows() const { return a1_mine_; }
  size_t memory() const;

 private:
  // Rows asked of their owners: `want` (global rows; each owner's ascending)
  // is received rank after rank; `send_at` lists this rank's rows asked,
  // asking rank after rank; the row counts per rank each way.
  struct Asks {
    std::vector<int64_t> recv;  // the rows received, in their order
    std::vector<int32_t> send_at;
    std::vector<int64_t> send_rows, recv_rows;
  };
  void plan_asks(const Reducer& red, const RankRows& rr, const std::vector<int32_t>& local,
                 const std::vector<int64_t>& want, Asks& a);
  // The ring's rows of K from their owners: the pattern (plan) or the values.
  void fetch_ring(const Reducer& red, const BlockMatrix& mine, bool pattern);
  void finest_smoother(const Reducer& red, const BlockMatrix& mine, const Multigrid& mg, bool whole, bool fresh);
  void power_iteration(const Reducer& red, RankRows& rr, const BlockMatrix& mine, const MultigridSettings& ms,
                       bool fresh);
  // Level 1's rows of this rank's points: T (K P) on the rows held.
  void level_one(const BlockMatrix& mine, const Multigrid& mg, bool pattern);
  // Chebyshev of degree 1 (one step from zero before and after): every
  // entry the cycle reads follows from the right-hand side's entries there,
  // so it is exchanged once and the ghosts' steps are repeated here; with
  // the gather, two rounds of messages a cycle. Other degrees exchange
  // before each product.
  void apply_one_step(const Reducer& red, const BlockMatrix& mine, Multigrid& mg, const double* b, double* s);
  void apply_steps(const Reducer& red, const BlockMatrix& mine, Multigrid& mg, const double* b, double* s);
  // The residual at the ring's rows (x whole there).
  void ring_residual(const double* b, const double* x, double* r) const;
  // v's ghost entries from their owners (v: `width` doubles a row, this rank's layout).
  void exchange(const Reducer& red, double* v, int width = 3);
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
  bool patterned_ = false;  // the products' patterns follow the plan
  int64_t own_ = 0;
  std::vector<int64_t> global_;       // this rank's row -> its global row
  std::vector<int64_t> ghosts_;       // global rows, ascending
  std::vector<int64_t> rows_;         // this rank's layout -> global row (its rows, then the ghosts)
  // The ring: other ranks' rows whose residual the restriction reads, as
  // received (owner after owner, ascending): their place in this rank's
  // layout, their rows of K (global columns) and those columns in the layout.
  std::vector<int32_t> ring_;
  BlockMatrix ring_k_;
  std::vector<int32_t> ring_col_;
  std::vector<int32_t> ring_of_;      // a ghost's place in the ring (-1: none), by layout row - own
  Asks ring_asks_, ghost_asks_;
  std::vector<int64_t> ring_send_blocks_;  // blocks sent per rank (the ring's rows asked of this rank)
  std::vector<int32_t> kcol_;         // K's blocks' columns in this rank's layout
  std::vector<int64_t> coarse_;       // level-1 points this rank restricts to (ascending)
  std::vector<int32_t> tcol_;         // their restriction rows' columns, this rank's layout
  std::vector<int64_t> tstart_;       // where each of them starts in tcol_
  std::vector<int64_t> coarse_of_;    // level-1 point -> its place in the ranks' concatenation
  std::vector<int64_t> coarse_rows_;  // level-1 points per rank
  std::vector<int64_t> gather_counts_;  // their values per rank (3 each)
  std::vector<int32_t> recv_at_;  // the ghosts' places, in the order received (owner after owner)
  std::vector<int64_t> send_bytes_, recv_bytes_, gather_bytes_, wide_send_, wide_recv_;
  std::vector<double> sbuf_, rbuf_;
  // The finest smoother: its polynomial (own, or the whole levels'), the
  // inverse diagonal blocks of the layout's rows (9 each), the power
  // iteration's vector on this rank's rows and whole.
  Chebyshev cheb_;
  const Chebyshev* ch_ = nullptr;
  std::vector<double> dinv_, eig_, eig_all_;
  // Level 1's rows: K P on the rows held (this rank's, the ring's), this rank's rows of T (K P).
  BlockMatrix ap_own_, ap_ring_, a1_mine_;
  PatternScratch pattern_;
  SlotMaps slots_;
  // This rank's vectors: x and the residual (rows and ghosts), the
  // smoother's workspaces (rows), level 1's whole right-hand side and
  // correction, this rank's part of it and the concatenation.
  std::vector<double> x_, res_, r_, d_, z_, b1_, x1_, b1_mine_, b1_cat_, bl_;
  int64_t exchanged_ = 0, build_bytes_ = 0;
  double below_ = 0;  // the last cycle's seconds in level 1 and below
};

}  // namespace drape
