#include "solver/multigrid/coarse_solve.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <stdexcept>

namespace drape {

struct CoarseSolve::Impl {
  Eigen::SparseMatrix<double> A;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
};

CoarseSolve::CoarseSolve() : impl_(std::make_unique<Impl>()) {}
CoarseSolve::~CoarseSolve() = default;

void CoarseSolve::factor(const BlockMatrix& K, bool pattern) {
  const int64_t n = 3 * K.rows;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(9 * size_t(K.blocks()));
  for (int64_t r = 0; r < K.rows; ++r)
    for (int64_t k = K.start[r]; k < K.start[r + 1]; ++k)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) t.emplace_back(int(3 * r + i), int(3 * K.col[k] + j), K.val[9 * k + 3 * i + j]);
  impl_->A.resize(int(n), int(n));
  impl_->A.setFromTriplets(t.begin(), t.end());
  if (pattern) impl_->ldlt.analyzePattern(impl_->A);
  impl_->ldlt.factorize(impl_->A);
  if (impl_->ldlt.info() != Eigen::Success) throw std::runtime_error("multigrid: the coarsest level's factorisation failed");
}

void CoarseSolve::solve(const double* b, double* x) const {
  const int n = int(impl_->A.rows());
  Eigen::Map<const Eigen::VectorXd> bb(b, n);
  Eigen::Map<Eigen::VectorXd> xx(x, n);
  xx = impl_->ldlt.solve(bb);
}

}  // namespace drape
