// Newton's linear solves on the box drape at the finest mesh, each
// preconditioner from the same state: the cloth is stepped (Jacobi, fixed
// dt) to --time, then every variant runs the next --steps steps from that
// state, and the linear iterations, Newton iterations and seconds per phase
// are reported side by side (ratios from one run).
// Kernel timings are the calling thread's CPU seconds (one thread by default).
//   linear_solve [--size 129] [--time 0.12] [--dt 5e-4] [--steps 5] [--threads 1] [--sweep] [--modes] [--out FILE.json]
//     [--counts] [--stretch-reversal R] [--bend-scale F] [--floor-only] [--contact-scale F] [--solve-dt S...]
//     [--fitted [--fit-vectors 8] [--fit-sweeps 30] [--fit-ratio 30] [--fit-cycles 0] [--fit-levels N]
//      [--fit-tikhonov 1e-3] [--fit-wide] [--fit-free-sums] [--fit-full-blocks] [--two-grid 1] [--two-grid-cubic]]
// --fitted: the bilinear against the fitted P only, with how well each
// interpolates the test vectors; --two-grid, --two-grid-cubic: two-grid
// cycles on the finest level with richer coarse spaces (experiments).
// Which physics makes the multigrid's count grow: --counts solves once with
// the bilinear V-cycle, point and line smoothing, and nothing else; the
// scene's stretch reversal (band kinks), the fabric's bending (both change
// the state reached) and a floor-only scene (contact without hanging sides)
// are set before stepping; the contact stiffness and the solve's dt (the
// mass term) are changed at the state, so that only the operator differs.
#include <omp.h>

#include <ctime>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "io/json.hpp"
#include "landing_state.hpp"

namespace drape {
namespace {

const char* name(Interpolation ip) {
  return ip == Interpolation::Smoothed ? "smoothed" : ip == Interpolation::Fitted ? "fitted" : "bilinear";
}

// The fitted interpolation's settings (--fit-*), and whether only the
// bilinear and fitted P are compared (--fitted).
MultigridSettings fit_settings;
bool fitted_only = false;
bool counts_only = false;
int two = 0;
bool cubic = false;

struct Variant {
  std::string name;
  Preconditioner pc;
  MultigridSettings mg;
};

struct Result {
  std::string name;
  int linear = 0, newton = 0, unconverged = 0, levels = 0;
  double seconds = 0, cpu = 0, precondition = 0, setup = 0, products = 0;
};

// The error that one V-cycle reduces least: e <- (I - M^-1 K) e from a fixed
// rough start, 40 times; its reduction factor in the K-norm, the share of
// |e|^2 on the box's top, its sides and the floor, by component, and how
// rough it is along i and along j (per component, 0 smooth, 1 changing sign
// every particle): which modes the cycle leaves.
void worst_mode(Simulation& w, const BlockMatrix& K, const std::vector<int64_t>& ids, int n, const MultigridSettings& ms,
                const char* label) {
  Multigrid mg(ms);
  mg.setup(K, ids, n, n, 1);
  const size_t m = 3 * ids.size();
  std::vector<double> e(m), ke(m), c(m);
  for (size_t k = 0; k < m; ++k) e[k] = std::sin(double(k * k % 1009));
  auto knorm = [&] {
    K.multiply(e.data(), ke.data());
    double s = 0;
    for (size_t k = 0; k < m; ++k) s += e[k] * ke[k];
    return std::sqrt(s);
  };
  double before = knorm(), factor = 0;
  for (int it = 0; it < 40; ++it) {
    for (double& v : e) v /= before;
    K.multiply(e.data(), ke.data());
    mg.apply(ke.data(), c.data());
    for (size_t k = 0; k < m; ++k) e[k] -= c[k];
    const double after = knorm();
    factor = after;  // e had K-norm 1
    before = after;
  }
  const double top = w.scene.obstacle.center[2] + 0.5 * w.scene.obstacle.size[2];
  double where[3][3] = {};  // region (top, sides, floor) x component
  std::vector<int32_t> row(size_t(n) * n, -1);
  for (size_t r = 0; r < ids.size(); ++r) row[ids[r]] = int32_t(r);
  double rough[2][3] = {}, total[3] = {};
  for (size_t r = 0; r < ids.size(); ++r) {
    const double h = w.cloth.z[3 * ids[r] + 2];
    const int region = h > top - 0.01 ? 0 : h > 0.01 ? 1 : 2;
    for (int k = 0; k < 3; ++k) {
      where[region][k] += e[3 * r + k] * e[3 * r + k];
      total[k] += e[3 * r + k] * e[3 * r + k];
    }
    const int i = int(ids[r] / n), j = int(ids[r] % n);
    const int32_t nb[2] = {i + 1 < n ? row[ids[r] + n] : -1, j + 1 < n ? row[ids[r] + 1] : -1};
    for (int d = 0; d < 2; ++d)
      if (nb[d] >= 0)
        for (int k = 0; k < 3; ++k) {
          const double df = e[3 * r + k] - e[3 * size_t(nb[d]) + k];
          rough[d][k] += df * df;
        }
  }
  const double all = total[0] + total[1] + total[2];
  std::printf("worst mode, %s: K-norm factor per cycle %.3f; |e|^2 top/sides/floor x,y,z:", label, factor);
  for (int g = 0; g < 3; ++g) std::printf(" [%.2f %.2f %.2f]", where[g][0] / all, where[g][1] / all, where[g][2] / all);
  std::printf("; roughness along i x,y,z %.2f %.2f %.2f, along j %.2f %.2f %.2f\n", rough[0][0] / (4 * total[0]),
              rough[0][1] / (4 * total[1]), rough[0][2] / (4 * total[2]), rough[1][0] / (4 * total[0]),
              rough[1][1] / (4 * total[1]), rough[1][2] / (4 * total[2]));
}

// How well the finest level's interpolation, bilinear and fitted (to 8 test
// vectors), reproduces test vectors from their values on the coarse points:
// |v - P v_c| / |v| over the 8 and for a 9th held out, the vectors relaxed by
// the smoother (A e = 0, Chebyshev of degree fit_sweeps) or by 5 bilinear
// V-cycles; and how low their energy is (v^T K v / v^T D v).
void fit_diagnostic(const BlockMatrix& K, const std::vector<int64_t>& ids, int n) {
  std::vector<int32_t> scratch(size_t(n) * n, -1);
  const std::vector<int64_t> coarse = coarse_points(ids, n, n, 1);
  const Prolongation P0 = make_prolongation(ids, coarse, n, n, 1, scratch);
  Prolongation P = fitted_pattern(ids, coarse, n, n, 1, fit_settings.fit_wide, scratch);
  for (size_t k = 0; k < ids.size(); ++k) scratch[ids[k]] = int32_t(k);
  std::vector<int64_t> fine_row;
  for (int64_t p : coarse) fine_row.push_back(scratch[p]);
  const int64_t m = 3 * K.rows;
  const int count = 8;
  for (int source = 0; source < 2; ++source) {
    std::vector<double> v, zero, kv(static_cast<size_t>(m)), c(static_cast<size_t>(m));
    random_vectors(K.rows, count + 1, v);
    Chebyshev cheb;
    cheb.setup(K, fit_settings.fit_sweeps, fit_settings.fit_ratio);
    if (source == 0) {
      relax_vectors(K, cheb, count + 1, v, zero);
    } else {
      Multigrid mg{MultigridSettings{}};
      mg.setup(K, ids, n, n, 1);
      for (int t = 0; t <= count; ++t)
        for (int it = 0; it < 5; ++it) {
          double* e = &v[size_t(t) * m];
          K.multiply(e, kv.data());
          mg.apply(kv.data(), c.data());
          for (int64_t i = 0; i < m; ++i) e[i] -= c[i];
        }
    }
    fit_prolongation(K, P0, fine_row, count, v, fit_settings.fit_tikhonov, fit_settings.fit_keep_sums,
                     fit_settings.fit_full_blocks, P);
    double err[2][2] = {}, rq = 0, share = 0;  // err: [P0, P][fitted set, held out]
    std::vector<double> vc;
    for (int t = 0; t <= count; ++t) {
      const double* x = &v[size_t(t) * m];
      std::vector<double> one(x, x + m);
      inject_vectors(fine_row, K.rows, 1, one, vc);
      double vv = 0, vkv = 0, vdv = 0;
      K.multiply(x, kv.data());
      for (int64_t i = 0; i < m; ++i) {
        vv += x[i] * x[i];
        vkv += x[i] * kv[i];
      }
      for (int64_t r = 0; r < K.rows; ++r) {
        const double* d = K.block(r, int32_t(r));
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) vdv += x[3 * r + a] * d[3 * a + b] * x[3 * r + b];
      }
      rq += vkv / vdv / (count + 1);
      double cc = 0;
      for (double q : vc) cc += q * q;
      share += cc / vv * double(K.rows) / double(coarse.size()) / (count + 1);
      for (int which = 0; which < 2; ++which) {
        std::fill(c.begin(), c.end(), 0.0);
        prolong_add(which ? P : P0, vc.data(), c.data());
        double ee = 0;
        for (int64_t i = 0; i < m; ++i) ee += (x[i] - c[i]) * (x[i] - c[i]);
        err[which][t == count] += t == count ? std::sqrt(ee / vv) : std::sqrt(ee / vv) / count;
      }
    }
    std::printf("test vectors by %s: v^T K v / v^T D v %.2e; mean square on the coarse points / overall %.2f; "
                "|v - P v_c| / |v| bilinear %.3f (held out %.3f), fitted %.3f (held out %.3f)\n",
                source ? "5 bilinear V-cycles" : "the smoother", rq, share, err[0][0], err[0][1], err[1][0], err[1][1]);
  }
}

// Preconditioned CG on A x = b from 0 to |r| <= 1e-8 |b|: the iterations.
int pcg(const BlockMatrix& A, const std::vector<double>& b, const std::function<void(const double*, double*)>& M) {
  const size_t n = b.size();
  std::vector<double> x(n, 0.0), r = b, z(n), p(n), ap(n);
  auto dot = [&](const std::vector<double>& u, const std::vector<double>& v) {
    double d = 0;
    for (size_t k = 0; k < n; ++k) d += u[k] * v[k];
    return d;
  };
  const double target = 1e-16 * dot(b, b);
  M(r.data(), z.data());
  p = z;
  double rz = dot(r, z);
  for (int it = 1; it <= 5000; ++it) {
    A.multiply(p.data(), ap.data());
    const double a = rz / dot(p, ap);
    for (size_t k = 0; k < n; ++k) {
      x[k] += a * p[k];
      r[k] -= a * ap[k];
    }
    if (dot(r, r) <= target) return it;
    M(r.data(), z.data());
    const double rz1 = dot(r, z);
    for (size_t k = 0; k < n; ++k) p[k] = z[k] + rz1 / rz * p[k];
    rz = rz1;
  }
  return 5000;
}

// PCG iterations with a two-grid cycle: the smoother, Q's Galerkin coarse
// operator solved exactly, the smoother again; its blocks in coarse_blocks.
int two_grid_iterations(const BlockMatrix& K, Chebyshev& smoother, const Prolongation& Q,
                        const std::vector<double>& b, int64_t& coarse_blocks) {
  BlockMatrix AP, Ac;
  galerkin(K, Q, AP, Ac, true);
  CoarseSolve solve;
  solve.factor(Ac, true);
  coarse_blocks = Ac.blocks();
  std::vector<double> r(b.size()), bc(3 * size_t(Q.coarse())), xc(bc.size());
  return pcg(K, b, [&](const double* rhs, double* x) {
    smoother.smooth(K, rhs, x, true);
    K.residual(rhs, x, r.data());
    restrict_to(Q, r.data(), bc.data());
    solve.solve(bc.data(), xc.data());
    prolong_add(Q, xc.data(), x);
    smoother.smooth(K, rhs, x, false);
  });
}

// Two functions per coarse node (adaptive smoothed aggregation's way of
// adding near-null vectors, Brezina et al. 2004), as a two-grid experiment
// on the finest level: P = [P0 | T P0], T_f = the 3 x 3 block [t1 t2 t3] at
// fine point f of three vectors left by 5 bilinear V-cycles, so that the
// coarse space holds each t_k (times any bilinear envelope) besides P0's
// fields. PCG iterations with the two-grid cycle (point Chebyshev, Galerkin
// coarse operator solved exactly) with P0 alone and with P, against the
// V-cycle: whether a richer coarse space would flatten the count.
void two_functions(const BlockMatrix& K, const std::vector<int64_t>& ids, int n, int sets) {
  std::vector<int32_t> scratch(size_t(n) * n, -1);
  const std::vector<int64_t> coarse = coarse_points(ids, n, n, 1);
  const Prolongation P0 = make_prolongation(ids, coarse, n, n, 1, scratch);
  const int64_t m = 3 * K.rows, nc = int64_t(coarse.size());
  std::vector<double> t, kv(static_cast<size_t>(m)), c(static_cast<size_t>(m));
  random_vectors(K.rows, 3 * sets, t);
  Multigrid vc{MultigridSettings{}};
  vc.setup(K, ids, n, n, 1);
  for (int k = 0; k < 3 * sets; ++k)
    for (int it = 0; it < 5; ++it) {
      double* e = &t[size_t(k) * m];
      K.multiply(e, kv.data());
      vc.apply(kv.data(), c.data());
      for (int64_t i = 0; i < m; ++i) e[i] -= c[i];
    }
  Prolongation P;
  P.P.rows = K.rows;
  P.P.start.assign(size_t(K.rows) + 1, 0);
  for (int64_t f = 0; f < K.rows; ++f) {
    for (int set = 0; set <= sets; ++set)
      for (int64_t q = P0.P.start[f]; q < P0.P.start[f + 1]; ++q) {
        const double w = P0.P.val[9 * q];
        P.P.col.push_back(int32_t(P0.P.col[q] + set * nc));
        for (int j = 0; j < 3; ++j)  // column-major, as BlockMatrix stores blocks
          for (int i = 0; i < 3; ++i)
            P.P.val.push_back(set ? w * t[size_t(3 * (set - 1) + j) * m + 3 * f + i] : (i == j ? w : 0.0));
      }
    P.P.start[f + 1] = int64_t(P.P.col.size());
  }
  transpose(P.P, (sets + 1) * nc, P.T);
  std::vector<double> b(static_cast<size_t>(m));
  for (int64_t k = 0; k < m; ++k) b[k] = std::cos(double(k));
  Chebyshev smoother;
  smoother.setup(K, 1, 10);
  for (int rich = 0; rich < 2; ++rich) {
    const Prolongation& Q = rich ? P : P0;
    int64_t coarse_blocks = 0;
    const int its = two_grid_iterations(K, smoother, Q, b, coarse_blocks);
    std::printf("two-grid, P0%s: %d iterations (coarse: %lld nodes, %lld blocks)\n",
                rich ? (" and " + std::to_string(3 * sets) + " V-cycle vectors per coarse point").c_str() : "", its,
                (long long)Q.coarse(), (long long)coarse_blocks);
  }
  std::printf("V-cycle, bilinear: %d iterations\n", pcg(K, b, [&](const double* rhs, double* x) { vc.apply(rhs, x); }));
}

// Cubic (Lagrange, 4 coarse lines where there are 4, else 3 or 2) in place
// of linear interpolation along each grid direction, on the finest level:
// where K is of fourth order (the hanging sides' bending across the weak
// direction), bilinear P and R = P^T are of too low an order for the
// Galerkin coarse operator (orders of P and R summing to more than the
// operator's are needed), cubic ones are not. Two-grid PCG as above.
Prolongation cubic_prolongation(const std::vector<int64_t>& fine, const std::vector<int64_t>& coarse, int n) {
  std::vector<int32_t> at(size_t(n) * n, -1);
  for (size_t k = 0; k < coarse.size(); ++k) at[coarse[k]] = int32_t(k);
  auto on = [&](int i) { return i % 2 == 0 || i == n - 1; };
  auto weights = [&](int i, std::vector<std::pair<int, double>>& out) {
    out.clear();
    if (on(i)) {
      out.emplace_back(i, 1.0);
      return;
    }
    std::vector<int> x;
    if (i - 3 >= 0) x.push_back(i - 3);
    x.push_back(i - 1);
    x.push_back(i + 1);
    if (i + 1 < n - 1) x.push_back(std::min(i + 3, n - 1));
    for (size_t a = 0; a < x.size(); ++a) {
      double w = 1;
      for (size_t b = 0; b < x.size(); ++b)
        if (b != a) w *= double(i - x[b]) / double(x[a] - x[b]);
      out.emplace_back(x[a], w);
    }
  };
  Prolongation P;
  P.P.rows = int64_t(fine.size());
  P.P.start.assign(fine.size() + 1, 0);
  std::vector<std::pair<int, double>> wi, wj;
  for (size_t f = 0; f < fine.size(); ++f) {
    weights(int(fine[f] / n), wi);
    weights(int(fine[f] % n), wj);
    std::vector<std::pair<int32_t, double>> row;
    for (const auto& [a, u] : wi)
      for (const auto& [b, v] : wj)
        if (at[size_t(a) * n + b] >= 0) row.emplace_back(at[size_t(a) * n + b], u * v);
    std::sort(row.begin(), row.end());
    for (const auto& [c, w] : row) {
      P.P.col.push_back(c);
      const double blk[9] = {w, 0, 0, 0, w, 0, 0, 0, w};
      P.P.val.insert(P.P.val.end(), blk, blk + 9);
    }
    P.P.start[f + 1] = int64_t(P.P.col.size());
  }
  transpose(P.P, int64_t(coarse.size()), P.T);
  return P;
}

void two_grid_cubic(const BlockMatrix& K, const std::vector<int64_t>& ids, int n) {
  std::vector<int32_t> scratch(size_t(n) * n, -1);
  const std::vector<int64_t> coarse = coarse_points(ids, n, n, 1);
  const Prolongation P0 = make_prolongation(ids, coarse, n, n, 1, scratch);
  const Prolongation P3 = cubic_prolongation(ids, coarse, n);
  const int64_t m = 3 * K.rows;
  std::vector<double> b(static_cast<size_t>(m));
  for (int64_t k = 0; k < m; ++k) b[k] = std::cos(double(k));
  Chebyshev smoother;
  smoother.setup(K, 1, 10);
  for (int cubic = 0; cubic < 2; ++cubic) {
    const Prolongation& Q = cubic ? P3 : P0;
    int64_t coarse_blocks = 0;
    const int its = two_grid_iterations(K, smoother, Q, b, coarse_blocks);
    std::printf("two-grid, %s P: %d iterations (coarse blocks %lld)\n", cubic ? "cubic" : "bilinear", its,
                (long long)coarse_blocks);
  }
}

// One solve to 1e-8 from the state with preconditioner pc (multigrid
// settings ms): the iterations; CPU seconds (set-up and solve) in *cpu.
int one_solve(Simulation& w, Preconditioner pc, const MultigridSettings& ms, Timers& t, double* cpu) {
  SolverSpec spec = w.scene.solver;
  spec.preconditioner = pc;
  TimeLoop loop(w.cloth, w.model, w.lists, w.tiling, w.policy, w.red(), spec);
  loop.newton().set_multigrid(ms);
  double* z = w.cloth.z.data();
  loop.evaluator().settled_cost(z);
  const std::clock_t c0 = std::clock();
  const int its = loop.newton().linear_solve(loop.evaluator(), z, 5000, 1e-8, t);
  *cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
  return its;
}

// --counts: the bilinear V-cycle's iterations with point smoothing, line
// smoothing on every level, and lines on the finest one or two only.
void counts(Simulation& w) {
  MultigridSettings point, line, line1, line2;
  line.smoothing = line1.smoothing = line2.smoothing = Smoothing::Line;
  line1.line_levels = 1;
  line2.line_levels = 2;
  const std::pair<const char*, MultigridSettings> cases[] = {
      {"point smoothing", point}, {"line smoothing", line}, {"lines on the finest level", line1},
      {"lines on the 2 finest levels", line2}};
  for (const auto& [label, ms] : cases) {
    Timers t;
    double cpu = 0;
    const int its = one_solve(w, Preconditioner::Multigrid, ms, t, &cpu);
    std::printf("counts: %s %d iterations, cpu %.3f s\n", label, its, cpu);
  }
  std::fflush(stdout);
}

// What one preconditioned iteration and one set-up cost, in stiffness
// products: assembling K, the levels' set-up, a V-cycle, K's block product.
void kernel_times(Simulation& w, bool modes) {
  Evaluator& ev = w.loop->evaluator();
  double* z = w.cloth.z.data();
  ev.settled_cost(z);
  std::vector<double> diag(w.cloth.z.size()), v(w.cloth.z.size(), 0.0), kv(w.cloth.z.size());
  ev.stiffness_diagonal(z, diag.data());
  for (int64_t p : w.lists.particles.items)
    for (int k = 0; k < 3; ++k) v[3 * p + k] = 1e-3 * std::sin(double(3 * p + k));
  const double product = per_call([&] { ev.stiffness_product(z, v.data(), kv.data()); });
  BlockMatrix K;
  const double assemble = per_call([&] { ev.assemble_stiffness(K); });
  const std::vector<int64_t>& ids = w.lists.particles.items;
  const int n = w.cloth.grid.ni;
  std::vector<double> r(3 * ids.size()), x(3 * ids.size());
  for (size_t k = 0; k < r.size(); ++k) r[k] = std::cos(double(k));
  const double matvec = per_call([&] { K.multiply(r.data(), x.data()); });
  if (fitted_only) fit_diagnostic(K, ids, n);
  if (fitted_only && two > 0) two_functions(K, ids, n, two);
  if (fitted_only && cubic) two_grid_cubic(K, ids, n);
  if (modes) {
    // How far below D^-1 A's top the smoother's 12-step power estimate is,
    // level by level (3000 steps taken as the truth).
    Multigrid probe{MultigridSettings{}};
    probe.setup(K, ids, n, n, 1);
    for (int l = 0; l + 1 < probe.levels(); ++l) {
      const BlockMatrix& A = probe.matrix(l);
      Chebyshev c;
      c.setup(A, 1, 10);
      const double quick = c.estimate();
      std::vector<double> v(3 * A.rows), u(v.size()), t(v.size());
      for (size_t k = 0; k < v.size(); ++k) v[k] = std::sin(1.0 + double(k * k % 101));
      double lam = 0;
      for (int it = 0; it < 3000; ++it) {
        double nv = 0;
        for (double q : v) nv += q * q;
        nv = std::sqrt(nv);
        for (double& q : v) q /= nv;
        A.multiply(v.data(), u.data());
        for (int64_t r = 0; r < A.rows; ++r)
          for (int i = 0; i < 3; ++i)
            t[3 * r + i] = c.dinv()[9 * r + 3 * i] * u[3 * r] + c.dinv()[9 * r + 3 * i + 1] * u[3 * r + 1] +
                           c.dinv()[9 * r + 3 * i + 2] * u[3 * r + 2];
        lam = 0;
        for (double q : t) lam += q * q;
        lam = std::sqrt(lam);
        v = t;
      }
      std::printf("level %d: D^-1 A's top: 12-step estimate %.4f, 3000 steps %.4f\n", l, quick, lam);
    }
    MultigridSettings point, line;
    line.smoothing = Smoothing::Line;
    worst_mode(w, K, ids, n, point, "point smoothing");
    worst_mode(w, K, ids, n, line, "line smoothing");
    MultigridSettings fitted = fit_settings;
    fitted.interpolation = Interpolation::Fitted;
    worst_mode(w, K, ids, n, fitted, "fitted P");
  }
  std::printf("stiffness product %.3f ms; K assembled %.2f products, K x %.2f products (%lld blocks)\n",
              1e3 * product, assemble / product, matvec / product, (long long)K.blocks());
  for (Interpolation ip : {Interpolation::Bilinear, Interpolation::Smoothed, Interpolation::Fitted})
    for (int degree : {1, 2, 3}) {
      if ((fitted_only || ip == Interpolation::Fitted) && degree > 1) continue;
      if (fitted_only && ip == Interpolation::Smoothed) continue;
      MultigridSettings ms = ip == Interpolation::Fitted ? fit_settings : MultigridSettings{degree, 10.0, 100};
      ms.interpolation = ip;
      Multigrid mg(ms);
      mg.setup(K, ids, n, n, 1);
      const double setup = per_call([&] { mg.setup(K, ids, n, n, 1); });
      uint64_t stamp = 1;  // a new stamp each call: K's pattern taken as new (self-contact's pairs built again)
      const double repattern = per_call([&] { mg.setup(K, ids, n, n, ++stamp); });
      const double cycle = per_call([&] { mg.apply(r.data(), x.data()); });
      std::printf("%s, degree %d: %d levels; set-up (values) %.2f products, (new pattern) %.2f, V-cycle %.2f products\n",
                  name(ip), degree, mg.levels(), setup / product, repattern / product, cycle / product);
      if (degree == 1)
        for (const MultigridLevelStats& l : mg.stats())
          std::printf("  level: %lld points, %lld blocks, stride %d, set-up %.3f s, cycles %.3f s\n",
                      (long long)l.points, (long long)l.blocks, l.stride, l.setup_seconds, l.seconds);
    }
  if (!fitted_only) {
    MultigridSettings ms;
    ms.smoothing = Smoothing::Line;
    Multigrid mg(ms);
    mg.setup(K, ids, n, n, 1);
    const double setup = per_call([&] { mg.setup(K, ids, n, n, 1); });
    const double cycle = per_call([&] { mg.apply(r.data(), x.data()); });
    std::printf("bilinear, line smoothing: %d levels; set-up (values) %.2f products, V-cycle %.2f products\n",
                mg.levels(), setup / product, cycle / product);
    for (const MultigridLevelStats& l : mg.stats())
      std::printf("  level: %lld points, %lld blocks, stride %d, set-up %.3f s, cycles %.3f s (%lld)\n",
                  (long long)l.points, (long long)l.blocks, l.stride, l.setup_seconds, l.seconds, (long long)l.cycles);
  }
  // One linear solve to 1e-8 from this state, each preconditioner: how the
  // counts grow with the grid (the loose Newton solves hide it). Seconds:
  // set-up (K assembled, levels built) and solve, CPU time of this thread.
  struct OneSolve {
    const char* name;
    Preconditioner pc;
    Interpolation ip;
    int smoothed_levels;
    Smoothing sm = Smoothing::Point;
  };
  const OneSolve solves[] = {{"jacobi", Preconditioner::Jacobi, Interpolation::Bilinear, 0},
                             {"multigrid bilinear", Preconditioner::Multigrid, Interpolation::Bilinear, 0},
                             {"multigrid line", Preconditioner::Multigrid, Interpolation::Bilinear, 0, Smoothing::Line},
                             {"multigrid smoothed (finest)", Preconditioner::Multigrid, Interpolation::Smoothed, 1},
                             {"multigrid smoothed (2 finest)", Preconditioner::Multigrid, Interpolation::Smoothed, 2},
                             {"multigrid smoothed", Preconditioner::Multigrid, Interpolation::Smoothed, 1000},
                             {"multigrid fitted", Preconditioner::Multigrid, Interpolation::Fitted, 1000}};
  for (const OneSolve& o : solves) {
    const bool fit = o.ip == Interpolation::Fitted;
    if (fitted_only && !fit && std::string(o.name) != "multigrid bilinear") continue;
    MultigridSettings ms = fit ? fit_settings : MultigridSettings{};
    ms.interpolation = o.ip;
    if (!fit) ms.smoothed_levels = o.smoothed_levels;
    ms.smoothing = o.sm;
    Timers t;
    double cpu = 0;
    const int its = one_solve(w, o.pc, ms, t, &cpu);
    std::printf("one solve to 1e-8, %-30s %4d iterations, cpu %.3f s (wall: set-up+diagonal %.3f, precondition %.3f)\n",
                (std::string(o.name) + ":").c_str(), its, cpu, t.seconds[kScaling], t.seconds[kPrecondition]);
  }
  std::fflush(stdout);
}

int run(int argc, char** argv) {
  CLI::App app{"Newton's linear solves: Jacobi and multigrid from one drape state"};
  int n = 129, steps = 5, threads = 1;
  double time = 0.12, dt = 5e-4;
  std::string out;
  bool sweep = false, modes = false;
  app.add_flag("--modes", modes, "the error one V-cycle reduces least, point and line smoothing: where, how rough");
  app.add_flag("--sweep", sweep, "every smoother degree 1-3 and ratio 4, 10, 30 (else ratio 10)");
  app.add_option("--size", n, "particles per side")->check(CLI::Range(9, 4001));
  app.add_option("--time", time, "simulated seconds before the compared steps")->check(CLI::Range(0.0, 10.0));
  app.add_option("--dt", dt, "fixed time step, s")->check(CLI::Range(1e-6, 1e-1));
  app.add_option("--steps", steps, "steps compared (0: the kernels and one solve only)")->check(CLI::Range(0, 100000));
  app.add_option("--threads", threads, "OpenMP threads")->check(CLI::Range(1, 1024));
  app.add_option("--out", out, "JSON file");
  app.add_flag("--fitted", fitted_only, "compare the bilinear and the fitted P only");
  app.add_option("--two-grid", two, "with --fitted: two-grid cycles with P0, and P0 plus 3 x this many vectors per coarse point")
      ->check(CLI::Range(0, 4));
  app.add_flag("--two-grid-cubic", cubic, "with --fitted: two-grid cycles with bilinear and cubic P");
  double reversal = -1, bend_scale = 1, contact_scale = 1;
  std::vector<double> solve_dts;
  bool floor_only = false;
  app.add_flag("--counts", counts_only, "one solve with the bilinear V-cycle: point smoothing, lines on every level, on the 1 and 2 finest; nothing else");
  app.add_option("--stretch-reversal", reversal, "cloth.stretch_reversal (1: no kinks inside the bands)")->check(CLI::Range(0.0, 1e3));
  app.add_option("--bend-scale", bend_scale, "the fabric's bending (B and 2HB) times this")->check(CLI::Range(0.0, 1e6));
  app.add_flag("--floor-only", floor_only, "no box: the cloth 5 cm above the floor (lands at the same time)");
  app.add_option("--contact-scale", contact_scale, "at the state: the contact stiffness times this")->check(CLI::Range(0.0, 1e6));
  app.add_option("--solve-dt", solve_dts, "at the state: the solve's dt, s (the mass term; several: --counts for each)")
      ->check(CLI::Range(1e-7, 1.0));
  app.add_option("--fit-vectors", fit_settings.fit_vectors, "fitted P: test vectors")->check(CLI::Range(1, 64));
  app.add_option("--fit-sweeps", fit_settings.fit_sweeps, "fitted P: degree of their relaxation")->check(CLI::Range(1, 1000));
  app.add_option("--fit-ratio", fit_settings.fit_ratio, "fitted P: the relaxation damps [lmax / ratio, lmax]");
  app.add_option("--fit-cycles", fit_settings.fit_cycles, "fitted P: vectors relaxed by bilinear V-cycles (finest P only)");
  app.add_option("--fit-levels", fit_settings.smoothed_levels, "fitted P: on this many finest levels");
  app.add_option("--fit-tikhonov", fit_settings.fit_tikhonov, "fitted P: pull towards the bilinear weights");
  bool wide = false, free_sums = false;
  app.add_flag("--fit-full-blocks", fit_settings.fit_full_blocks, "fitted P: full 3 x 3 blocks (else diagonal)");
  app.add_flag("--fit-free-sums", free_sums, "fitted P: rows need not keep the bilinear row sums");
  app.add_flag("--fit-wide", wide, "fitted P: 6 coarse neighbours where P0 has 2 (else P0's)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  fit_settings.fit_wide = wide;
  fit_settings.fit_keep_sums = !free_sums;
  omp_set_num_threads(threads);
  Scene scene = landing_scene(n, dt);
  if (reversal >= 0) scene.cloth.stretch_reversal = reversal;
  if (floor_only) {
    scene.obstacle.shape = ObstacleShape::None;
    scene.cloth.height = 0.05;
  }
  Fabric fabric = load_fabric(scene.cloth.fabric);
  for (BendingKES& b : fabric.bending) {
    b.b *= bend_scale;
    b.hb *= bend_scale;
  }
  Simulation w(scene, fabric);
  step_to(w, time);
  w.model.contact.stiffness *= contact_scale;
  if (counts_only) {
    for (size_t k = 0; k < std::max<size_t>(1, solve_dts.size()); ++k) {
      if (!solve_dts.empty()) {
        w.model.dt = w.model.dt_prev = solve_dts[k];
        std::printf("solve dt %g s\n", solve_dts[k]);
      }
      counts(w);
    }
    return 0;
  }
  if (!solve_dts.empty()) w.model.dt = w.model.dt_prev = solve_dts[0];
  kernel_times(w, modes);
  const Cloth saved = w.cloth;
  const Model saved_model = w.model;
  std::vector<Variant> variants;
  if (steps > 0) variants.push_back({"jacobi", Preconditioner::Jacobi, {}});
  for (int degree : {1, 2, 3})
    for (double ratio : {4.0, 10.0, 30.0})
      if (steps > 0 && (sweep || ratio == 10.0))
        variants.push_back({"multigrid-d" + std::to_string(degree) + "-r" + std::to_string(int(ratio)),
                          Preconditioner::Multigrid, MultigridSettings{degree, ratio, 100}});
  if (steps > 0) {
    MultigridSettings line;
    line.smoothing = Smoothing::Line;
    variants.push_back({"multigrid-line", Preconditioner::Multigrid, line});
  }
  std::vector<Result> results;
  for (const Variant& v : variants) {
    w.cloth = saved;
    w.model = saved_model;
    SolverSpec spec = scene.solver;
    spec.preconditioner = v.pc;
    TimeLoop loop(w.cloth, w.model, w.lists, w.tiling, w.policy, w.red(), spec);
    loop.newton().set_multigrid(v.mg);
    Timers t;
    Result r{v.name};
    const double t0 = omp_get_wtime();
    const std::clock_t c0 = std::clock();  // CPU time: the machine may be shared
    for (int k = 0; k < steps; ++k) {
      const StepStats st = loop.step(t);
      r.linear += st.iterations;
      r.newton += st.newton_iterations;
      r.unconverged += !st.converged;
    }
    r.seconds = omp_get_wtime() - t0;
    r.cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
    r.precondition = t.seconds[kPrecondition];
    r.setup = t.seconds[kScaling];
    r.products = t.seconds[kGradient];
    r.levels = loop.newton().multigrid_levels();
    results.push_back(r);
    std::printf("%-20s linear %6d  newton %5d  per newton %6.2f  unconverged %d  levels %d  %8.3f s, cpu %8.3f s "
                "(precondition %.3f, set-up+diagonal %.3f, products+costs %.3f)\n",
                r.name.c_str(), r.linear, r.newton, double(r.linear) / std::max(1, r.newton), r.unconverged,
                r.levels, r.seconds, r.cpu, r.precondition, r.setup, r.products);
    std::fflush(stdout);
  }
  if (!out.empty()) {
    Json j;
    j.begin_object();
    j.value("size", n).value("time", time).value("dt", dt).value("steps", steps).value("threads", threads);
    j.begin_array("variants");
    for (const Result& r : results) {
      j.begin_object();
      j.value("name", r.name).value("linear_iterations", r.linear).value("newton_iterations", r.newton);
      j.value("unconverged", r.unconverged).value("levels", r.levels).value("seconds", r.seconds).value("cpu_seconds", r.cpu);
      j.value("precondition_seconds", r.precondition).value("setup_seconds", r.setup);
      j.end_object();
    }
    j.end_array().end_object();
    std::ofstream(out) << j.str() << "\n";
  }
  return 0;
}

}  // namespace
}  // namespace drape

int main(int argc, char** argv) { return drape::run(argc, argv); }
