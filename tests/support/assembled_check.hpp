#pragma once
// K assembled (Evaluator::assemble_stiffness, the multigrid's finest level)
// against the matrix-free product it must equal: A v = K v on the free
// particles to 1e-12 of K v's largest free entry, one row a free particle,
// and A symmetric block by block. Shared by the tests of each term K holds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "solver/multigrid/block_matrix.hpp"
#include "scenes.hpp"

namespace drape::test {

// `diag` receives the stiffness diagonal at z (the product's scaling pass).
inline void expect_assembled_is_the_product(Simulation& w, const std::string& label, std::vector<double>& diag) {
  Evaluator& ev = w.loop->evaluator();
  const size_t n = w.cloth.z.size();
  std::vector<double> v(n, 0.0), kv(n, 0.0);
  diag.assign(n, 0.0);
  ev.stiffness_diagonal(w.cloth.z.data(), diag.data());
  BlockMatrix A;
  ev.assemble_stiffness(A);
  const std::vector<int64_t>& ids = w.lists.particles.items;
  ASSERT_EQ(A.rows, int64_t(ids.size())) << label;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> vc(3 * ids.size()), av(3 * ids.size());
  for (size_t r = 0; r < ids.size(); ++r)
    for (int k = 0; k < 3; ++k) v[3 * ids[r] + k] = vc[3 * r + k] = u(rng);
  ev.stiffness_product(w.cloth.z.data(), v.data(), kv.data());
  A.multiply(vc.data(), av.data());
  double scale = 0;
  for (size_t r = 0; r < ids.size(); ++r)
    for (int k = 0; k < 3; ++k) scale = std::max(scale, std::fabs(kv[3 * ids[r] + k]));
  for (size_t r = 0; r < ids.size(); ++r)
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(av[3 * r + k], kv[3 * ids[r] + k], 1e-12 * scale)
          << "particle " << ids[r] << " axis " << k << " " << label;
  for (int64_t r = 0; r < A.rows; ++r)
    for (int64_t b = A.start[r]; b < A.start[r + 1]; ++b) {
      const double* t = A.block(A.col[b], int32_t(r));
      ASSERT_NE(t, nullptr) << "no block (" << A.col[b] << ", " << r << ") " << label;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) EXPECT_NEAR(A.val[9 * b + 3 * i + j], t[3 * j + i], 1e-12 * scale) << label;
    }
}

}  // namespace drape::test
