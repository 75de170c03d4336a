#pragma once
// The coarsest level solved directly: Eigen's sparse LDL^T of the assembled
// (symmetric positive definite) coarse operator, factored once per setup.
#include <memory>
#include <vector>

#include "solver/multigrid/block_matrix.hpp"

namespace drape {

class CoarseSolve {
 public:
  CoarseSolve();
  ~CoarseSolve();
  // Analyses the pattern when `pattern`, then factors A's values.
  void factor(const BlockMatrix& A, bool pattern);
  void solve(const double* b, double* x) const;

 private:
  void set_pattern(const BlockMatrix& A);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace drape
