// The multigrid preconditioner (src/solver/multigrid/) on K assembled from
// a cloth: its transfers, a two-level cycle's reduction of a smooth error
// (the same at every spacing), preconditioned CG's iteration counts as the
// grid is refined, and the cycle's independence of the thread count.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <functional>
#include <random>

#include "solver/multigrid/multigrid.hpp"
#include "world.hpp"

namespace drape::test {
namespace {

// An n x n cloth of 1 m, stretched 1 % in its plane (tension everywhere:
// K has its geometric term), a corner clamped, a long step (0.02 s: the
// stiffness, not the mass, dominates K).
struct Stretched {
  World w;
  BlockMatrix K;
  explicit Stretched(int n) : w(flat_scene(n, n, 1.0, 1.0), test_fabric()) {
    w.cloth.flags[0] |= kFixed;
    w.rebuild();
    for (int64_t p = 0; p < w.cloth.grid.n(); ++p)
      for (int k = 0; k < 2; ++k) w.cloth.z[3 * p + k] *= 1.01;
    w.model.dt = w.model.dt_prev = 0.02;
    Evaluator& ev = w.loop->evaluator();
    ev.settled_cost(w.cloth.z.data());
    std::vector<double> diag(w.cloth.z.size());
    ev.stiffness_diagonal(w.cloth.z.data(), diag.data());
    ev.assemble_stiffness(K);
  }
  const std::vector<int64_t>& ids() const { return w.lists.particles.items; }
};

double energy(const BlockMatrix& A, const std::vector<double>& e) {
  std::vector<double> ae(e.size());
  A.multiply(e.data(), ae.data());
  double s = 0;
  for (size_t k = 0; k < e.size(); ++k) s += e[k] * ae[k];
  return s;
}

// Preconditioned CG on A x = b from 0 to |r| <= tol |b|: the iterations.
int pcg(const BlockMatrix& A, const std::vector<double>& b, const std::function<void(const double*, double*)>& M,
        double tol) {
  const size_t n = b.size();
  std::vector<double> x(n, 0.0), r = b, s(n), p(n), ap(n);
  auto dot = [&](const std::vector<double>& u, const std::vector<double>& v) {
    double d = 0;
    for (size_t k = 0; k < n; ++k) d += u[k] * v[k];
    return d;
  };
  const double target = tol * tol * dot(b, b);
  M(r.data(), s.data());
  p = s;
  double rs = dot(r, s);
  for (int it = 1; it <= 1000; ++it) {
    A.multiply(p.data(), ap.data());
    const double a = rs / dot(p, ap);
    for (size_t k = 0; k < n; ++k) {
      x[k] += a * p[k];
      r[k] -= a * ap[k];
    }
    if (dot(r, r) <= target) return it;
    M(r.data(), s.data());
    const double rs1 = dot(r, s);
    for (size_t k = 0; k < n; ++k) p[k] = s[k] + rs1 / rs * p[k];
    rs = rs1;
  }
  return 1000;
}

TEST(Multigrid, ProlongationInterpolatesAndSkipsNonUnknowns) {
  Stretched s(9);
  const int n = 9;
  const std::vector<int64_t>& fine = s.ids();
  std::vector<int64_t> coarse = coarse_points(fine, n, n, 1);
  EXPECT_EQ(coarse.size(), size_t(5 * 5 - 1));  // every other line; the clamped corner is no point
  std::vector<int32_t> scratch(size_t(n) * n, -1);
  const Prolongation P = make_prolongation(fine, coarse, n, n, 1, scratch);
  std::vector<double> ones(3 * coarse.size(), 1.0), out(3 * fine.size(), 0.0);
  prolong_add(P, ones.data(), out.data());
  for (size_t f = 0; f < fine.size(); ++f) {
    const int i = int(fine[f] / n), j = int(fine[f] % n);
    const bool by_corner = i <= 1 && j <= 1;  // interpolates from the clamped corner (no correction there)
    if (by_corner) EXPECT_LT(out[3 * f], 1.0) << i << "," << j;
    else EXPECT_DOUBLE_EQ(out[3 * f], 1.0) << i << "," << j;
  }
  // Restriction is P's transpose: <P x, y> = <x, P^T y>.
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> xc(3 * coarse.size()), yf(3 * fine.size()), px(3 * fine.size(), 0.0), ry(3 * coarse.size());
  for (double& v : xc) v = u(rng);
  for (double& v : yf) v = u(rng);
  prolong_add(P, xc.data(), px.data());
  restrict_to(P, yf.data(), ry.data());
  double a = 0, b = 0;
  for (size_t k = 0; k < yf.size(); ++k) a += px[k] * yf[k];
  for (size_t k = 0; k < xc.size(); ++k) b += xc[k] * ry[k];
  EXPECT_NEAR(a, b, 1e-12 * std::fabs(a));
}

// One two-level cycle (exact coarse solve) on a smooth error: its energy
// drops by a factor that does not grow as the grid is refined.
TEST(Multigrid, TwoLevelReductionOfASmoothErrorIndependentOfSpacing) {
  std::vector<double> factors;
  for (int n : {17, 33, 65}) {
    Stretched s(n);
    const int64_t level1 = int64_t(coarse_points(s.ids(), n, n, 1).size());
    MultigridSettings st;
    st.coarsest = level1;
    Multigrid mg(st);
    mg.setup(s.K, s.ids(), n, n, 1);
    ASSERT_EQ(mg.levels(), 2);
    std::vector<double> e(3 * s.ids().size()), ae(e.size()), c(e.size());
    for (size_t r = 0; r < s.ids().size(); ++r) {
      const double x = double(s.ids()[r] / n) / (n - 1), y = double(s.ids()[r] % n) / (n - 1);
      e[3 * r] = std::sin(M_PI * x) * std::sin(2 * M_PI * y);
      e[3 * r + 2] = std::sin(3 * M_PI * x) * std::sin(M_PI * y);
    }
    const double before = energy(s.K, e);
    s.K.multiply(e.data(), ae.data());
    mg.apply(ae.data(), c.data());
    for (size_t k = 0; k < e.size(); ++k) e[k] -= c[k];
    factors.push_back(std::sqrt(energy(s.K, e) / before));
  }
  std::printf("two-level energy reduction at 17, 33, 65: %.3f %.3f %.3f\n", factors[0], factors[1], factors[2]);
  for (double f : factors) EXPECT_LT(f, 0.5);
  EXPECT_LT(factors[2], 1.5 * factors[0]) << factors[0] << " " << factors[1] << " " << factors[2];
}

// Preconditioned CG to 1e-8: multigrid's count stays flat from 33 to 129
// while the diagonal's grows with the spacing.
TEST(Multigrid, PreconditionedIterationsStayFlatAsTheGridIsRefined) {
  std::vector<int> mg_its, jac_its;
  const int sizes[] = {33, 65, 129};
  for (int n : sizes) {
    Stretched s(n);
    Multigrid mg;
    mg.setup(s.K, s.ids(), n, n, 1);
    EXPECT_GE(mg.levels(), 3);
    std::mt19937_64 rng(2);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<double> b(3 * s.ids().size());
    for (double& v : b) v = u(rng);
    mg_its.push_back(pcg(s.K, b, [&](const double* r, double* x) { mg.apply(r, x); }, 1e-8));
    if (n > 65) continue;  // the diagonal's count at 129 would take seconds
    std::vector<double> dinv(b.size());
    for (int64_t r = 0; r < s.K.rows; ++r)
      for (int k = 0; k < 3; ++k) dinv[3 * r + k] = 1.0 / s.K.block(r, int32_t(r))[4 * k];
    jac_its.push_back(pcg(s.K, b, [&](const double* r, double* x) {
      for (size_t k = 0; k < dinv.size(); ++k) x[k] = dinv[k] * r[k];
    }, 1e-8));
  }
  for (size_t k = 0; k < mg_its.size(); ++k)
    std::printf("PCG to 1e-8 at %d: multigrid %d iterations\n", sizes[k], mg_its[k]);
  std::printf("Jacobi: %d at 33, %d at 65\n", jac_its[0], jac_its[1]);
  EXPECT_LE(mg_its[2], 1.5 * mg_its[0]);
  EXPECT_LE(mg_its[2], 50);
  EXPECT_GE(jac_its[1], 1.5 * jac_its[0]);  // the problem does get harder with h
}

// A V-cycle is the same, bit for bit, on 1, 2 and 3 threads.
TEST(Multigrid, CycleIndependentOfTheThreadCount) {
  Stretched s(33);
  std::vector<double> ref;
  for (int t : {1, 2, 3}) {
    omp_set_num_threads(t);
    Multigrid mg;
    mg.setup(s.K, s.ids(), 33, 33, 1);
    std::vector<double> b(3 * s.ids().size()), x(b.size());
    for (size_t k = 0; k < b.size(); ++k) b[k] = std::cos(0.1 * double(k));
    mg.apply(b.data(), x.data());
    if (ref.empty()) ref = x;
    else EXPECT_EQ(x, ref) << t << " threads";
  }
  omp_set_num_threads(1);
}

}  // namespace
}  // namespace drape::test
