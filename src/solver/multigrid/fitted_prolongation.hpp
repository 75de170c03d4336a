#pragma once
// Interpolation fitted to the operator's near-null vectors, on the geometric
// hierarchy's coarse points (the idea of bootstrap AMG, Brandt, Brannick,
// Kahl and Livshits 2011, and of adaptive smoothed aggregation, Brezina et
// al. 2004): a few vectors that the level's smoother reduces slowly are
// found by relaxing A e = 0 from pseudo-random starts; each fine point's
// 3 x 3 blocks on its coarse neighbours are then the least-squares fit
// that interpolates those vectors from their values on the coarse points,
// optionally with the bilinear P's row sums kept exactly (translations
// interpolated as P0 does), and a small pull towards the bilinear weights
// (a well-posed fit where the vectors say little). Coarse points keep
// injection.
#include <cstdint>
#include <vector>

#include "solver/multigrid/block_matrix.hpp"
#include "solver/multigrid/smoother.hpp"
#include "solver/multigrid/transfer.hpp"

namespace drape {

// The fitted P's pattern: each fine point's coarse neighbours, P0's or,
// where `wide`, also the next coarse lines' points along the grid line a
// point shares with the coarse level (6 in place of 2). Values zero.
// `scratch` as for make_prolongation.
Prolongation fitted_pattern(const std::vector<int64_t>& fine_ids, const std::vector<int64_t>& coarse_ids, int ni,
                            int nj, int stride, bool wide, std::vector<int32_t>& scratch);

// `count` vectors of 3 `rows` doubles each, one after the other, from a
// hash of their index (the same on any thread count).
void random_vectors(int64_t rows, int count, std::vector<double>& v);
// Each vector relaxed towards A e = 0 by one application of `relax` (a
// Chebyshev polynomial of the degree wanted, set up for A), then scaled to
// unit mean square.
void relax_vectors(const BlockMatrix& A, Chebyshev& relax, int count, std::vector<double>& v, std::vector<double>& zero);
// The vectors' values on the coarse points (`fine_row[c]`: coarse point c's
// row on the fine level): the next level's starting vectors.
void inject_vectors(const std::vector<int64_t>& fine_row, int64_t fine_rows, int count, const std::vector<double>& v,
                    std::vector<double>& out);
// P's values (its pattern from fitted_pattern) fitted to the vectors `v` on
// A's level. `fine_row` as above; `tikhonov`: the pull towards P0's weights,
// relative to the fit's own scale; `keep_sums`: each row's blocks sum to
// P0's row sum times I exactly (P interpolates translations as P0 does),
// else the vectors alone decide (a near-null space that is not smooth);
// `full_blocks`: each component from all three of the neighbours' (3 k
// unknowns a row, more than the vectors usually are: underdetermined),
// else from the same component only (diagonal blocks, k unknowns).
void fit_prolongation(const BlockMatrix& A, const Prolongation& P0, const std::vector<int64_t>& fine_row, int count,
                      const std::vector<double>& v, double tikhonov, bool keep_sums, bool full_blocks,
                      Prolongation& P);

}  // namespace drape
