#include "solver/multigrid/coarse_solve.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <stdexcept>
#include <vector>

namespace drape {

struct CoarseSolve::Impl {
  Eigen::SparseMatrix<double> A;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  std::vector<int64_t> from;  // per stored entry of A: its number in the blocks' values
};

CoarseSolve::CoarseSolve() : impl_(std::make_unique<Impl>()) {}
CoarseSolve::~CoarseSolve() = default;

// A's pattern from K's, each entry's value its number in K.val (exact in a
// double): read back, the numbers map A's stored entries to K's values.
void CoarseSolve::set_pattern(const BlockMatrix& K) {
  const int64_t n = 3 * K.rows;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(9 * size_t(K.blocks()));
  for (int64_t r = 0; r < K.rows; ++r)
    for (int64_t k = K.start[r]; k < K.start[r + 1]; ++k)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) t.emplace_back(int(3 * r + i), int(3 * K.col[k] + j), double(9 * k + 3 * i + j));
  impl_->A.resize(int(n), int(n));
  impl_->A.setFromTriplets(t.begin(), t.end());
  impl_->A.makeCompressed();
  const int64_t nnz = impl_->A.nonZeros();
  impl_->from.resize(size_t(nnz));
  for (int64_t p = 0; p < nnz; ++p) impl_->from[p] = int64_t(impl_->A.valuePtr()[p]);
}

void CoarseSolve::factor(const BlockMatrix& K, bool pattern) {
  if (pattern) set_pattern(K);
  // Values only: copied through the kept map, so that refactoring with the
  // same pattern builds nothing.
  double* v = impl_->A.valuePtr();
  const int64_t* from = impl_->from.data();
  for (size_t p = 0, e = impl_->from.size(); p < e; ++p) v[p] = K.val[size_t(from[p])];
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
