#pragma once
// The grid transfers between two multigrid levels of the cloth's own grid
// hierarchy: level l's points are the free particles on the grid lines
// i, j = multiples of 2^l (and the far border's line, where the grid size is
// not k 2^l + 1, as the quadtree clips its cells). A point of level l that
// is not one of level l + 1 takes the bilinear interpolation of its (2 or 4)
// neighbours on level l + 1's lines; neighbours that are not unknowns
// (fixed, inactive, hanging) carry no correction and drop out. The same
// weights for x, y and z: P is scalar per particle.
#include <cstdint>
#include <vector>

#include "solver/multigrid/block_matrix.hpp"

namespace drape {

struct Prolongation {
  int64_t fine = 0, coarse = 0;
  std::vector<int64_t> start;  // fine + 1
  std::vector<int32_t> col;    // coarse point
  std::vector<double> w;
  // Its transpose (per coarse point, fine points ascending).
  std::vector<int64_t> t_start;
  std::vector<int32_t> t_row;
  std::vector<double> t_w;
};

// Level l + 1's points (ids into the grid, in level l's order) and P from
// them to level l's points `ids` (stride 2^l on a grid ni x nj). `scratch`:
// one int per grid particle, all -1 (left so).
std::vector<int64_t> coarse_points(const std::vector<int64_t>& ids, int ni, int nj, int stride);
Prolongation make_prolongation(const std::vector<int64_t>& fine_ids, const std::vector<int64_t>& coarse_ids, int ni,
                               int nj, int stride, std::vector<int32_t>& scratch);

// x_fine += P x_coarse; b_coarse = P^T r_fine.
void prolong_add(const Prolongation& P, const double* xc, double* xf);
void restrict_to(const Prolongation& P, const double* rf, double* bc);

// Ac = P^T A P, the pattern set when `pattern` (else Ac's is reused), the
// values summed in a fixed order (any thread count, the same matrix).
void galerkin(const BlockMatrix& A, const Prolongation& P, BlockMatrix& Ac, bool pattern);

}  // namespace drape
