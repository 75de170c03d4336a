#pragma once
// Geometric multigrid over the cloth's own grid hierarchy, as the Newton
// step's preconditioner: levels of the free particles on every 2^l-th grid
// line (transfer.hpp), coarse operators by Galerkin product P^T A P, a
// Chebyshev smoother (smoother.hpp) or block lines (line_smoother.hpp), and
// the coarsest level solved by a sparse LDL^T (coarse_solve.hpp). One V-cycle from zero is the preconditioner: a
// symmetric positive definite operator, as linear CG needs. Everything sums
// in fixed orders: the same result on any thread count.
#include <cstdint>
#include <memory>
#include <vector>

#include "solver/memory_table.hpp"
#include "solver/multigrid/block_matrix.hpp"
#include "solver/multigrid/coarse_solve.hpp"
#include "solver/multigrid/fitted_prolongation.hpp"
#include "solver/multigrid/line_smoother.hpp"
#include "solver/multigrid/smoothed_prolongation.hpp"
#include "solver/multigrid/smoother.hpp"
#include "solver/multigrid/transfer.hpp"

namespace drape {

// How a coarse level's correction reaches the level above: bilinear
// interpolation of the displacements (P0), P0 smoothed by one damped
// block-Jacobi step in the fine operator (smoothed_prolongation.hpp), or
// weights fitted to vectors the smoother reduces slowly (fitted_prolongation.hpp).
enum class Interpolation { Bilinear, Smoothed, Fitted };
// The levels' smoother: Chebyshev on the point (3 x 3 block) diagonal, or
// block-line Gauss-Seidel along i and j (line_smoother.hpp), robust where K
// couples one grid direction much more strongly than the other.
enum class Smoothing { Point, Line };

struct MultigridSettings {
  int degree = 1;             // Chebyshev steps before and after the coarse correction (1 fastest at 129)
  double ratio = 10;          // the smoother damps D^-1 A's spectrum above lmax / ratio
  int64_t coarsest = 100;     // particles at most on the directly solved level
  Interpolation interpolation = Interpolation::Bilinear;  // the faster on the drape (set-up included)
  int smoothed_levels = 1000;  // the finest levels whose P is smoothed or fitted (the coarse operators widen with each)
  // Fitted interpolation: test vectors, the degree of the Chebyshev
  // relaxation of A e = 0 that makes them, over [lmax / fit_ratio, lmax],
  // the wide stencil (6 coarse neighbours where P0 has 2), the pull towards
  // P0, whether P's rows keep P0's sums (translations) exactly.
  int fit_vectors = 8;
  int fit_sweeps = 30;  // 10 left the twisted Laplacian's vectors rough (37, 60 iterations at 33, 65 against 13, 12)
  double fit_ratio = 30;
  bool fit_wide = false;  // the wide fit is worse conditioned (16 against 12 iterations there)
  double fit_tikhonov = 1e-3;
  bool fit_keep_sums = true;
  bool fit_full_blocks = false;  // components from each other's values too (else diagonal blocks)
  // > 0: the test vectors are relaxed by this many V-cycles with the
  // bilinear P (the modes the cycle leaves) and only the finest P is fitted.
  int fit_cycles = 0;
  Smoothing smoothing = Smoothing::Point;
  int line_sweeps = 1;  // line smoothing: sweeps (i-lines, then j-lines) before and after the coarse correction
  // Line smoothing on this many finest levels, the point smoother below:
  // the coarse levels' operators are averaged over 2^l particles and lines
  // there cost more than they save.
  int line_levels = 1000;
};

struct MultigridLevelStats {
  int64_t points = 0, blocks = 0;  // particles and 3 x 3 blocks of its operator
  int stride = 1;                  // its grid lines' spacing, in finest intervals
  int64_t cycles = 0;              // V-cycles that visited it
  double seconds = 0;              // in its smoother, residual and transfers (coarsest: the solve)
  double setup_seconds = 0;        // Galerkin product, smoother set-up or factorisation
};

class Multigrid {
 public:
  explicit Multigrid(MultigridSettings s = {}) : s_(s) {}
  // New settings: the next setup builds the levels afresh.
  void set_settings(const MultigridSettings& s) {
    s_ = s;
    stamp_ = 0;
    levels_.clear();
  }
  // Levels for A0, whose row r is grid particle ids[r] of an ni x nj grid.
  // The point sets and transfers are rebuilt when `ids` or the grid change,
  // the patterns when `stamp` (K's pattern's) changes or is 0, the values
  // every call. A0 must outlive the next apply.
  void setup(const BlockMatrix& A0, const std::vector<int64_t>& ids, int ni, int nj, uint64_t stamp);
  // The same in two halves, for a finest level that no one holds whole (its
  // rows divided over ranks: DividedLevel): the points and transfers, which
  // follow ids alone (returns whether the patterns are new: `fresh`); then,
  // once the caller has set level 1's operator (level_one()) and the finest
  // level's size (finest_blocks), the levels from 1 down.
  bool setup_points(const std::vector<int64_t>& ids, int ni, int nj, uint64_t stamp);
  // setup's second half: every level's values from A0 whole.
  void setup_values(const BlockMatrix& A0, bool fresh) {
    a0_ = &A0;
    build_from(0, fresh);
  }
  void setup_below(bool fresh, int64_t finest_blocks);
  BlockMatrix& level_one() { return levels_[1].A; }
  // Whether the finest level's transfer and smoother need no more than its
  // own rows of A0 and a ring around them (the bilinear P, point smoothing).
  bool finest_divisible() const {
    return finest_by_points() && !levels_[0].smoothed && !levels_[0].fitted;
  }
  const MultigridSettings& settings() const { return s_; }
  // Its arrays, by kind (the finest level's operator is the caller's).
  void memory(MemoryTable& t) const;
  // The next setup carries nothing over from earlier ones (the smoothers'
  // eigenvector estimates): a run restarted at a step builds what the
  // uninterrupted run built there.
  void forget() {
    for (Level& l : levels_) l.smoother.forget();
  }
  // x = M^-1 r: one V-cycle from x = 0 (3 doubles a row of A0).
  void apply(const double* r, double* x);
  int levels() const { return int(levels_.size()); }
  // Per level: its current size, and cycles and seconds over every build so far.
  const std::vector<MultigridLevelStats>& stats() const { return stats_; }
  const BlockMatrix& matrix(int l) const { return l == 0 ? *a0_ : levels_[l].A; }

  // What a finest level divided over ranks (DividedLevel) reads: whether
  // the finest level is smoothed by points with a level below it (else it
  // cannot be divided), its smoother and transfer, level l's particles;
  // the cycle from level 1 down (b1, x1: 3 a level-1 row), and the finest
  // level's part of a cycle counted (its seconds there). levels_built()
  // changes whenever the levels' points and patterns are rebuilt.
  bool finest_by_points() const { return levels() > 1 && !levels_[0].lines; }
  const Chebyshev& finest_smoother() const { return levels_[0].smoother; }
  const Prolongation& finest_transfer() const { return levels_[0].transfer(); }
  const std::vector<int64_t>& level_ids(int l) const { return levels_[size_t(l)].ids; }
  void cycle_below(const double* b1, double* x1) { cycle(1, b1, x1); }
  void count_finest(double seconds) {
    ++stats_[0].cycles;
    stats_[0].seconds += seconds;
  }
  uint64_t levels_built() const { return levels_built_; }

 private:
  struct Level {
    std::vector<int64_t> ids;  // grid particles, in the finest level's order
    int stride = 1;
    BlockMatrix A;             // P^T A P of the level above (level 0: a0_)
    Prolongation P0;           // bilinear, from the next level down to this one
    Prolongation P;            // P0 smoothed (where `smoothed`) or fitted (where `fitted`)
    BlockMatrix AP0, AP;       // A P0 and A P: the products' workspaces (AP: its pattern; values in ap_values_)
    bool smoothed = false, fitted = false;
    const Prolongation& transfer() const { return smoothed || fitted ? P : P0; }
    bool lines = false;  // smoothed by lines (else the point Chebyshev)
    Chebyshev smoother;
    Chebyshev relax;                 // fitted: the test vectors' relaxation
    std::vector<int64_t> fine_row;   // fitted: the next level's points' rows here
    std::vector<double> tests, zero;  // fitted: the test vectors on this level
    LineSmoother line;
    std::vector<double> b, x, r;
  };
  void cycle(int l, const double* b, double* x);
  void smooth(Level& L, const BlockMatrix& A, const double* b, double* x, bool pre);
  void build_levels(const std::vector<int64_t>& ids, int ni, int nj);
  void fit(int l);
  void cycle_vectors(const BlockMatrix& A);
  void build_from(int first, bool fresh);
  void galerkin_below(int l, bool fresh);

  MultigridSettings s_;
  std::vector<Level> levels_;
  std::vector<MultigridLevelStats> stats_;
  const BlockMatrix* a0_ = nullptr;
  CoarseSolve coarse_;
  std::vector<double> ap_values_;     // every level's A P values in turn (galerkin_below)
  std::unique_ptr<Multigrid> probe_;  // fit_cycles: the bilinear cycle that relaxes the test vectors
  uint64_t stamp_ = 0;
  uint64_t levels_built_ = 0;
  int ni_ = 0, nj_ = 0;
  int64_t rows_ = -1;
};

}  // namespace drape
