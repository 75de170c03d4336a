#pragma once
// The grid transfers between two multigrid levels of the cloth's own grid
// hierarchy: level l's points are the free particles on the grid lines
// i, j = multiples of 2^l (and the far border's line, where the grid size is
// not k 2^l + 1, as the quadtree clips its cells). A point of level l that
// is not one of level l + 1 takes the bilinear interpolation of its (2 or 4)
// neighbours on level l + 1's lines; neighbours that are not unknowns
// (fixed, inactive, hanging) carry no correction and drop out. The bilinear
// weights are the same for x, y and z; a smoothed P (smoothed_prolongation.hpp)
// mixes them, so P is kept as 3 x 3 blocks either way.
#include <cstdint>
#include <vector>

#include "solver/multigrid/block_matrix.hpp"

namespace drape {

struct Prolongation {
  BlockMatrix P;  // fine rows, coarse columns
  BlockMatrix T;  // P^T: coarse rows, fine columns ascending, blocks transposed
  // Every block w I (the bilinear P): the transfers and the Galerkin
  // product read w alone, a third of the multiplications, the same sums
  // (the other terms are exact zeros).
  bool scalar = false;
  int64_t fine() const { return P.rows; }
  int64_t coarse() const { return T.rows; }
};

// Level l + 1's points (ids into the grid, in level l's order): those of
// level l's points `ids` (stride 2^l on a grid ni x nj) on the lines of
// stride 2^(l+1).
std::vector<int64_t> coarse_points(const std::vector<int64_t>& ids, int ni, int nj, int stride);
// The bilinear P from `coarse_ids` to `fine_ids`. `scratch`: one int per grid
// particle, all -1 (left so).
Prolongation make_prolongation(const std::vector<int64_t>& fine_ids, const std::vector<int64_t>& coarse_ids, int ni,
                               int nj, int stride, std::vector<int32_t>& scratch);
// T from P (pattern and values).
void transpose(const BlockMatrix& P, int64_t coarse, BlockMatrix& T);

// x_fine += P x_coarse; b_coarse = P^T r_fine.
void prolong_add(const Prolongation& P, const double* xc, double* xf);
void restrict_to(const Prolongation& P, const double* rf, double* bc);

// Ac = P^T A P, as P^T (A P) with AP kept between calls; the patterns set
// when `pattern` (else AP's and Ac's are reused), the values summed in a
// fixed order (any thread count, the same matrix).
void galerkin(const BlockMatrix& A, const Prolongation& P, BlockMatrix& AP, BlockMatrix& Ac, bool pattern);

}  // namespace drape
