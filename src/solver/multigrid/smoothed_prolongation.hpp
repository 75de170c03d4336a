#pragma once
// The smoothed prolongation of smoothed aggregation (Vanek, Mandel, Brezina
// 1996): P = (I - w D^-1 A) P0, one damped block-Jacobi step on each of the
// bilinear P0's columns: each coarse basis function's energy drops where
// the operator is stiff, and what A kills (constants, linear fields where
// A's rows sum to zero) P0 and P interpolate alike. Its columns are wider
// (A's stencil), so the coarse operators are denser; MultigridSettings says
// on how many of the finest levels it is used. w = 4 / (3 lmax(D^-1 A)).
#include <cstdint>
#include <vector>

#include "solver/multigrid/block_matrix.hpp"
#include "solver/multigrid/transfer.hpp"

namespace drape {

// P from P0 on the level of A, whose inverse diagonal blocks are `dinv` (9 a
// row) and whose D^-1 A has spectral radius about `lmax`. AP0: workspace, its
// pattern (and P's) set when `pattern`.
void smooth_prolongation(const BlockMatrix& A, const std::vector<double>& dinv, double lmax, const Prolongation& P0,
                         BlockMatrix& AP0, Prolongation& P, bool pattern);

}  // namespace drape
