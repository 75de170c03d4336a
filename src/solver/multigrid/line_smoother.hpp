#pragma once
// A block-line smoother for the multigrid's levels: block Gauss-Seidel over
// the level's grid lines, each line's unknowns updated together by an exact
// solve of the line's own couplings (the principal block of A on the line: a
// banded matrix of 3 x 3 blocks, factored once per set-up as L D L^T).
// Where A couples one grid direction far more strongly than the other (the
// draped cloth's tension along its hanging direction), point smoothing
// leaves the error smooth along the strong direction but rough across it,
// which full coarsening cannot represent; a line along the strong direction
// removes it. The strong direction changes over the cloth, so each sweep
// takes the lines along i, then those along j.
//
// Lines are coloured by their index modulo (the widest coupling across lines
// + 1): lines of one colour share no coupling, so a colour's lines are solved
// together (in parallel, each line its own result: the same on any thread
// count) and the sweep is exact block Gauss-Seidel. The post-smoothing sweep
// runs the colours and directions in reverse, the A-adjoint of the
// pre-smoothing one: the V-cycle stays symmetric, as CG needs, with no
// eigenvalue estimate and no damping to choose.
#include <cstdint>
#include <vector>

#include "solver/multigrid/block_matrix.hpp"

namespace drape {

class LineSmoother {
 public:
  // Lines of the level whose row r is grid particle ids[r] (grid ni x nj,
  // the level's lines every `stride` grid lines and the far border's) and
  // their factorisations. The lines are found again when `pattern`.
  void setup(const BlockMatrix& A, const std::vector<int64_t>& ids, int ni, int nj, int stride, bool pattern);
  // `sweeps` sweeps towards A x = b (x = 0 on entry when `zero`); `forward`:
  // i-lines then j-lines, colours ascending; else the reverse.
  void smooth(const BlockMatrix& A, const double* b, double* x, bool zero, bool forward, int sweeps);
  size_t held_bytes() const {
    size_t b = (w_.capacity() + r_.capacity()) * sizeof(double);
    for (const Direction& d : dir_)
      b += (d.order.capacity() + d.by_colour.capacity() + d.colour_rows.capacity() + d.colour_pos.capacity()) * 4 +
           (d.line_start.capacity() + d.colour_start.capacity() + d.colour_row_start.capacity()) * 8 +
           (d.dinv.capacity() + d.low.capacity()) * sizeof(double);
    return b;
  }
  // Colours per direction (i-lines, j-lines) and the band's width in blocks.
  int colours(int dir) const { return dir_[dir].colours; }
  int band() const { return dir_[0].band > dir_[1].band ? dir_[0].band : dir_[1].band; }

 private:
  struct Direction {
    std::vector<int32_t> order;       // the rows, line by line, in order along the line
    std::vector<int64_t> line_start;  // lines + 1 offsets into order
    std::vector<int32_t> by_colour;   // line numbers grouped by colour
    std::vector<int64_t> colour_start;
    // Per colour, its rows ascending and their positions in `order`: the
    // residuals and updates walk A's rows in memory order.
    std::vector<int32_t> colour_rows, colour_pos;
    std::vector<int64_t> colour_row_start;
    int colours = 1, band = 1;
    // Per position q in `order`: D^-1 (9) and L's blocks (q, q - d), d = 1..band (9 each).
    std::vector<double> dinv, low;
  };
  void find_lines(Direction& d, const BlockMatrix& A, const std::vector<int64_t>& ids, int nj, int stride, int dir);
  void factor(Direction& d, const BlockMatrix& A);
  void sweep_colour(const Direction& d, int colour, const BlockMatrix& A, const double* b, double* x, bool x_zero);
  void solve_line(const Direction& d, int64_t line, double* v) const;
  Direction dir_[2];
  std::vector<double> w_;  // the factorisation's L D blocks (one direction at a time)
  std::vector<double> r_;  // residuals, at rows' positions along the line (3 a position)
};

}  // namespace drape
