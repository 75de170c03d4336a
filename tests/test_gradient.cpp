// The analytic gradient against central differences of the total cost, term
// by term, on random states that put forces both inside and outside their
// KES bands and particles in contact; and the paper's numerical-gradient mode
// against the analytic one.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>

#include "amrc/criterion.hpp"
#include "solver/kernels.hpp"
#include "solver/loops.hpp"
#include "solver/multigrid/block_matrix.hpp"
#include "support/assembled_check.hpp"
#include "support/memory_rows.hpp"
#include "support/scenes.hpp"

namespace drape::test {
namespace {

struct Term {
  const char* name;
  bool newton, stretch, bend, shear;
  double memory;  // weight of the force memory term
  bool amrc = false;  // on an AMRC mesh with hanging particles
};

// A mesh with coarse leaves, fine leaves and hanging particles between them
// (some on sides clipped at the far border).
Quadtree amrc_tree() {
  Quadtree t = mixed_tree();
  t.refine(t.leaf_at(9, 9));
  return t;
}

// Random, well away from flat: positions jittered by 30% of h, forces drawn
// over several band widths, a sphere and the floor touching some particles.
std::unique_ptr<Simulation> random_world(unsigned seed, bool amrc = false) {
  Scene s = amrc ? flat_scene(13, 11, 0.12, 0.10) : flat_scene(7, 6, 0.06, 0.05);
  s.cloth.height = 0.004;
  s.cloth.bend_reversal = 5;  // the targets then move inside the bands
  s.cloth.shear_reversal = 3;
  s.cloth.stretch_reversal = 2;
  s.cloth.compression = 0.1;  // the jitter shortens some edges: their branch counts
  s.obstacle.shape = ObstacleShape::Sphere;
  s.obstacle.center = {0.0, 0.0, -0.02};
  s.obstacle.radius = 0.025;
  s.obstacle.floor = true;
  s.solver.dt = 2e-3;
  auto world = std::make_unique<Simulation>(s, test_fabric());
  Simulation& w = *world;
  if (amrc) w.set_tree(amrc_tree());
  w.cloth.flags[0] |= kFixed;  // a clamped corner: not an unknown
  w.rebuild();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  const double h = w.cloth.grid.hi;
  for (int64_t k = 0; k < 3 * w.cloth.grid.n(); ++k) w.cloth.z[k] += 0.3 * h * u(rng);
  const Layout& L = w.cloth.layout;
  for (int64_t k = L.tension(); k < L.moment(); ++k) w.cloth.z[k] = 40.0 * (1 + u(rng));
  for (int64_t k = L.moment(); k < L.shear(); ++k) w.cloth.z[k] = 2e-3 * u(rng);
  for (int64_t k = L.shear(); k < L.size(); ++k) w.cloth.z[k] = 3.0 * u(rng);
  // The step's history forces: near the current ones, as during a minimisation.
  std::vector<double> f1(w.cloth.z.size(), 0.0);  // laid out as z
  for (int64_t k = L.tension(); k < L.size(); ++k) f1[k] = w.cloth.z[k] * (1 + 0.05 * u(rng));
  w.model.dt = 2e-3;
  w.model.dt_prev = 1.5e-3;
  w.model.drag = 4.0;  // air drag in the Newton term
  w.loop->freeze_bend_axes();
  // As at a step's start: the bands' reversal folds the step-start strains
  // into the anchors.
  EXPECT_GT(w.model.bend[0].reversal(), 1.0);
  EXPECT_GT(w.model.stretch[1].reversal(), 1.0);
  EXPECT_GT(w.model.shear.reversal(), 1.0);
  w.loop->evaluator().hysteresis_anchors(w.cloth.x1.data(), f1.data());
  return world;
}

// Coulomb friction on the sphere and the floor, with a slip ramp as wide as
// the jitter's slips (about 3 mm), so that particles lie both on the ramp
// and beyond it. Returns how many particles a surface holds at x1.
int with_friction(Simulation& w) {
  w.model.contact.friction = 0.4;
  w.model.contact.floor_friction = 0.7;
  w.model.contact.slip = 1e-3;
  int held = 0;
  for (int64_t p : w.lists.particles.items) {
    double blk[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    held += friction_block(w.model.contact, &w.cloth.z[3 * p], &w.cloth.x1[3 * p], blk);
  }
  return held;
}

CostTerms term_cost(Simulation& w, std::vector<double>& z) { return w.loop->evaluator().evaluate(z.data(), nullptr); }

// (cp - cm) / 2h summed term by term: each difference then rounds at its own
// term's size, not at the total's (the tensions' share of the cost is
// orders of magnitude above what a moment or shear force moves).
double difference(const CostTerms& cp, const CostTerms& cm, double h) {
  return ((cp.newton - cm.newton) + (cp.stretch - cm.stretch) + (cp.bend - cm.bend) + (cp.shear - cm.shear)) /
         (2 * h);
}

// Central difference of the whole cost, unknown by unknown.
std::vector<double> central_difference(Simulation& w) {
  std::vector<double> z = w.cloth.z, g(z.size(), 0.0);
  const Layout& L = w.cloth.layout;
  auto scale = [&](int64_t k) {
    if (k < L.tension()) return w.cloth.grid.hi;
    if (k < L.moment()) return 10.0;
    if (k < L.shear()) return 0.1;  // steps of 1e-7 N*m/m: a finer one rounds to noise
    return 1.0;
  };
  std::vector<char> unknown(z.size(), 0);
  for (int64_t p : w.lists.particles.items)
    for (int k = 0; k < 3; ++k) unknown[3 * p + k] = 1;
  for (int64_t s : w.lists.edges.items) unknown[L.tension() + s] = 1;
  for (int64_t s : w.lists.triples.items) unknown[L.moment() + s] = 1;
  for (int64_t s : w.lists.shears.items) unknown[L.shear() + s] = 1;
  for (size_t k = 0; k < z.size(); ++k) {
    if (!unknown[k]) continue;
    const double h = 1e-6 * scale(int64_t(k)), z0 = z[k];
    z[k] = z0 + h;
    const CostTerms cp = term_cost(w, z);
    z[k] = z0 - h;
    const CostTerms cm = term_cost(w, z);
    z[k] = z0;
    g[k] = difference(cp, cm, h);
  }
  return g;
}

double max_abs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::fabs(x));
  return m;
}

const char* const kBlocks[4] = {"positions", "tensions", "moments", "shear forces"};

// The worst error of b against a in each block of unknowns (positions,
// tensions, moments, shear forces), relative to the largest entry of a or b
// in that block: the blocks differ by orders of magnitude, so a global
// maximum would let an error in the smaller blocks pass unseen (and a block
// a leaves at zero where b is not counts as an error of 1).
std::array<double, 4> block_errors(const Simulation& w, const std::vector<double>& a, const std::vector<double>& b) {
  const Layout& L = w.cloth.layout;
  const int64_t edges[5] = {0, L.tension(), L.moment(), L.shear(), L.size()};
  std::array<double, 4> out{};
  for (int blk = 0; blk < 4; ++blk) {
    double e = 0, scale = 0;
    int64_t at = edges[blk];
    for (int64_t k = edges[blk]; k < edges[blk + 1]; ++k) {
      scale = std::max({scale, std::fabs(a[k]), std::fabs(b[k])});
      if (std::fabs(a[k] - b[k]) > e) e = std::fabs(a[k] - b[k]), at = k;
    }
    out[blk] = scale > 0 ? e / scale : 0.0;
    if (getenv("DRAPE_DEBUG_GRADIENT"))
      printf("%s: worst unknown %lld: analytic %.10g numeric %.10g (block max %.3g): %.3g\n", kBlocks[blk],
             (long long)at, a[at], b[at], scale, out[blk]);
  }
  return out;
}

class GradientTerm : public ::testing::TestWithParam<Term> {};

TEST_P(GradientTerm, AnalyticMatchesCentralDifferences) {
  const Term t = GetParam();
  for (unsigned seed : {1u, 2u, 3u}) {
    const auto world = random_world(seed, t.amrc);
    Simulation& w = *world;
    if (t.amrc) {
      ASSERT_GE(w.lists.hanging.size(), 4u) << "the AMRC mesh should have hanging particles";
    }
    w.model.use_newton = t.newton;
    w.model.use_stretch = t.stretch;
    w.model.use_bend = t.bend;
    w.model.use_shear = t.shear;
    w.model.memory = t.memory;
    std::vector<double> ga(w.cloth.z.size());
    const CostTerms c = w.loop->evaluator().evaluate(w.cloth.z.data(), ga.data());
    ASSERT_GT(c.total(), 0.0) << t.name << ": the random state should cost something";
    ASSERT_GT(max_abs(ga), 0.0);
    const std::vector<double> gf = central_difference(w);
    const std::array<double, 4> e = block_errors(w, ga, gf);
    for (int blk = 0; blk < 4; ++blk) EXPECT_LE(e[blk], 1e-6) << t.name << ", seed " << seed << ": " << kBlocks[blk];
  }
}

INSTANTIATE_TEST_SUITE_P(EachTerm, GradientTerm,
                         ::testing::Values(Term{"newton", true, false, false, false, 0.0},
                                           Term{"stretch", false, true, false, false, 0.0},
                                           Term{"bend", false, false, true, false, 0.0},
                                           Term{"shear", false, false, false, true, 0.0},
                                           Term{"memory", false, false, false, false, 1.0},
                                           Term{"all", true, true, true, true, 1.0},
                                           Term{"amrc_newton", true, false, false, false, 0.0, true},
                                           Term{"amrc_bend", false, false, true, false, 0.0, true},
                                           Term{"amrc_all", true, true, true, true, 1.0, true}),
                         [](const auto& info) { return std::string(info.param.name); });

// The Newton term with Coulomb friction on the sphere and the floor (some
// particles on the slip ramp, some beyond): its gradient J^T r, with J
// friction's 3x3 block, against central differences. Plain and AMRC mesh.
TEST(Gradient, FrictionMatchesCentralDifferences) {
  for (bool amrc : {false, true}) {
    const auto world = random_world(5, amrc);
    Simulation& w = *world;
    ASSERT_GT(with_friction(w), 0);
    w.model.use_stretch = w.model.use_bend = w.model.use_shear = false;
    std::vector<double> ga(w.cloth.z.size());
    w.loop->evaluator().evaluate(w.cloth.z.data(), ga.data());
    const std::vector<double> gf = central_difference(w);
    EXPECT_LE(block_errors(w, ga, gf)[0], 1e-6) << (amrc ? "AMRC mesh" : "plain mesh");
  }
}

// The drape tester's disc instead of the sphere: particles over its top,
// beside its rim and off its round edge, with and without friction.
TEST(Gradient, DiscObstacleMatchesCentralDifferences) {
  for (bool friction : {false, true}) {
    const auto world = random_world(6);
    Simulation& w = *world;
    Obstacle& o = w.model.contact.obstacle;
    o.shape = ObstacleShape::Disc;
    o.center[0] = 0.002;
    o.center[1] = -0.001;
    o.center[2] = -0.002;
    o.half[2] = 0.005;
    o.radius = 0.017;
    int top = 0, rim = 0;
    for (int64_t p : w.lists.particles.items) {
      double n[3];
      if (disc_distance(o, &w.cloth.z[3 * p], n, nullptr) >= w.model.contact.thickness) continue;
      ++(std::fabs(n[2]) > 0.999 ? top : rim);
    }
    ASSERT_GT(top, 2);
    ASSERT_GT(rim, 2);
    if (friction) {
      ASSERT_GT(with_friction(w), 0);
    }
    w.model.use_stretch = w.model.use_bend = w.model.use_shear = false;
    std::vector<double> ga(w.cloth.z.size());
    w.loop->evaluator().evaluate(w.cloth.z.data(), ga.data());
    const std::vector<double> gf = central_difference(w);
    EXPECT_LE(block_errors(w, ga, gf)[0], 1e-6) << (friction ? "with friction" : "frictionless");
  }
}

TEST(Gradient, NumericModeMatchesAnalytic) {
  const auto world = random_world(7);
  Simulation& w = *world;
  std::vector<double> ga(w.cloth.z.size()), gn(w.cloth.z.size());
  const CostTerms ca = w.loop->evaluator().evaluate(w.cloth.z.data(), ga.data());
  const CostTerms cn = w.loop->evaluator().numeric_gradient(w.cloth.z.data(), gn.data());
  EXPECT_EQ(ca.total(), cn.total());
  // The mode differences each unknown's window of cost as a whole, with a
  // step of 1e-6 of the unknown's scale: the window's tension terms, far the
  // largest, round the moments' and shear forces' differences to a few parts
  // in 1e4 of their blocks (7e-4 and 5e-4 here). Those blocks are held to
  // that; positions and tensions to 1e-6.
  const std::array<double, 4> e = block_errors(w, ga, gn), tol = {1e-6, 1e-6, 2e-3, 2e-3};
  for (int blk = 0; blk < 4; ++blk) EXPECT_LE(e[blk], tol[blk]) << kBlocks[blk];
}

TEST(Gradient, NonUnknownsHaveZeroGradient) {
  const auto world = random_world(4);
  Simulation& w = *world;
  std::vector<double> ga(w.cloth.z.size(), 1.0);
  w.loop->evaluator().evaluate(w.cloth.z.data(), ga.data());
  for (int k = 0; k < 3; ++k) EXPECT_EQ(ga[k], 0.0) << "fixed particle 0";
  // The last particle of a row starts no warp... the last row has no warp edge.
  const int64_t last = w.cloth.grid.n() - 1;
  EXPECT_EQ(ga[w.cloth.layout.tension() + 2 * last], 0.0);
}

// A grid line that turns by a right angle about an axis normal to the
// bending axis n (n in the plane of both edges, as in a crumpled corner):
// the bend angle is that between the edges projected normal to n (here both
// along x: no bending about n), finite, with a gradient that matches central
// differences. With the plain e1.e2 both of atan2's arguments were zero.
TEST(BendKernel, RightAngleTurnAboutAnAxisNormalToTheBendingAxis) {
  const V3<double> n{0, 1, 0};
  const V3<double> a{-0.7, -0.7, 0}, b{0, 0, 0}, c{0.7, -0.7, 0};
  V3<double> g[3];
  const double th = bend_angle(a, b, c, n, g);
  ASSERT_TRUE(std::isfinite(th));
  EXPECT_NEAR(th, 0.0, 1e-15);
  const V3<double> x[3] = {a, b, c};
  const double eps = 1e-6;
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) {
      V3<double> xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]};
      (&xp[k].x)[i] += eps;
      (&xm[k].x)[i] -= eps;
      V3<double> unused[3];
      const double fd = (bend_angle(xp[0], xp[1], xp[2], n, unused) -
                         bend_angle(xm[0], xm[1], xm[2], n, unused)) / (2 * eps);
      const double an = (&g[k].x)[i];
      ASSERT_TRUE(std::isfinite(an));
      EXPECT_NEAR(an, fd, 1e-6 * (1 + std::fabs(fd))) << "particle " << k << " axis " << i;
    }
}

// The hand-derived Hessian-vector kernels (bend_gradient_hv, shear_cell_hv)
// against the same formulas on dual numbers, the reference: on jittered
// grid-like elements at the finest mesh's scale and random directions, the
// gradients bit for bit and H r to a relative 1e-9 of its largest entry (a
// dropped or mis-signed term is off by order one).
namespace {
double largest(const V3<double>* a, int n) {
  double m = 0;
  for (int k = 0; k < n; ++k) m = std::max({m, std::fabs(a[k].x), std::fabs(a[k].y), std::fabs(a[k].z)});
  return m;
}
void expect_hv_matches(const V3<double>* g, const V3<double>* hr, const V3<Dual>* gd, int n, int sample) {
  const double tol = 1e-9 * largest(hr, n);
  for (int k = 0; k < n; ++k) {
    EXPECT_EQ(g[k].x, gd[k].x.v) << "sample " << sample << " particle " << k;
    EXPECT_EQ(g[k].y, gd[k].y.v) << "sample " << sample << " particle " << k;
    EXPECT_EQ(g[k].z, gd[k].z.v) << "sample " << sample << " particle " << k;
    EXPECT_NEAR(hr[k].x, gd[k].x.d, tol) << "sample " << sample << " particle " << k;
    EXPECT_NEAR(hr[k].y, gd[k].y.d, tol) << "sample " << sample << " particle " << k;
    EXPECT_NEAR(hr[k].z, gd[k].z.d, tol) << "sample " << sample << " particle " << k;
  }
}
}  // namespace

TEST(ElementKernels, HandDerivedHessianVectorMatchesDualReference) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  const double h = 1e-3;
  auto jitter = [&](double x, double y, double amount) {
    return V3<double>{h * (x + amount * u(rng)), h * (y + amount * u(rng)), h * amount * u(rng)};
  };
  auto dir = [&] { return V3<double>{u(rng), u(rng), u(rng)}; };
  for (int sample = 0; sample < 500; ++sample) {
    const double amount = sample < 250 ? 0.1 : 0.4;
    // A triple along x about an axis near z (the cloth's normal).
    const V3<double> x[3] = {jitter(-1, 0, amount), jitter(0, 0, amount), jitter(1, 0, amount)};
    V3<double> n{0.2 * u(rng), 0.2 * u(rng), 1.0};
    n = (1.0 / std::sqrt(dot(n, n))) * n;
    const V3<double> r[3] = {dir(), dir(), dir()};
    V3<double> g[3], hr[3];
    bend_gradient_hv(x[0], x[1], x[2], n, r, g, hr);
    V3<Dual> xd[3], gd[3];
    for (int k = 0; k < 3; ++k) {
      const double rv[3] = {r[k].x, r[k].y, r[k].z};
      xd[k] = load3(&x[k].x, rv);
    }
    bend_gradient(xd[0], xd[1], xd[2], load3<Dual>(&n.x), gd);
    expect_hv_matches(g, hr, gd, 3, sample);
    // A cell [s, along i, along j, across].
    const V3<double> c[4] = {jitter(0, 0, amount), jitter(1, 0, amount), jitter(0, 1, amount),
                             jitter(1, 1, amount)};
    const V3<double> rc[4] = {dir(), dir(), dir(), dir()};
    V3<double> gc[4], hc[4];
    shear_cell_hv(c, rc, gc, hc);
    V3<Dual> cd[4], gcd[4];
    for (int k = 0; k < 4; ++k) {
      const double rv[3] = {rc[k].x, rc[k].y, rc[k].z};
      cd[k] = load3(&c[k].x, rv);
    }
    shear_cell<Dual, false>(cd, gcd);
    expect_hv_matches(gc, hc, gcd, 4, sample);
    if (HasFailure()) return;  // one sample's report is enough
  }
}

// Four triples side by side (bend_terms_four, bend_gradient_hv_four: in the
// lanes of a 4-double vector where the build has them) give each triple's
// scalar kernel numbers bit for bit: the atan2 arguments, the gradient and
// H r, four different triples at a time (a lane mixed up with another
// differs), straight to sharply bent, at the finest mesh's scale and a
// coarse one's, about axes near the cloth's normal.
TEST(TripleLanes, FourTriplesAreTheScalarKernelsBitForBit) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  auto same = [](const void* a, const void* b, size_t n) { return std::memcmp(a, b, n) == 0; };
  for (int sample = 0; sample < 2000; ++sample) {
    TripleFour t;
    V3<double> r[4][3];
    for (int l = 0; l < 4; ++l) {
      const double amount = (sample + l) % 3 == 0 ? 0.05 : (sample + l) % 3 == 1 ? 0.4 : 0.9;
      const double h = (sample + l) % 2 ? 1e-3 : 3e-2;
      auto jitter = [&](double x) {
        return V3<double>{h * (x + amount * u(rng)), h * amount * u(rng), h * amount * u(rng)};
      };
      t.a[l] = jitter(-1);
      t.b[l] = jitter(0);
      t.c[l] = jitter(1);
      V3<double> n{0.3 * u(rng), 0.3 * u(rng), 1.0};
      t.n[l] = (1.0 / std::sqrt(dot(n, n))) * n;
      for (V3<double>& rk : r[l]) rk = {u(rng), u(rng), u(rng)};
    }
    V3<double> g[4][3], hr[4][3];
    double s[4], co[4];
    bend_terms_four(t, g, s, co);
    V3<double> gh[4][3];
    bend_gradient_hv_four(t, r, gh, hr);
    for (int l = 0; l < 4; ++l) {
      V3<double> g1[3], gh1[3], hr1[3];
      double s1, co1;
      bend_terms(t.a[l], t.b[l], t.c[l], t.n[l], g1, s1, co1);
      bend_gradient_hv(t.a[l], t.b[l], t.c[l], t.n[l], r[l], gh1, hr1);
      ASSERT_TRUE(same(&s[l], &s1, sizeof s1) && same(&co[l], &co1, sizeof co1))
          << "sample " << sample << " lane " << l;
      ASSERT_TRUE(same(g[l], g1, sizeof g1)) << "sample " << sample << " lane " << l;
      ASSERT_TRUE(same(gh[l], gh1, sizeof gh1) && same(gh[l], g1, sizeof g1)) << "sample " << sample << " lane " << l;
      ASSERT_TRUE(same(hr[l], hr1, sizeof hr1)) << "sample " << sample << " lane " << l;
    }
  }
}

// The kernels' atan2 (angle_K.hpp) against std::atan2, in units in the last
// place of std's result: over every direction at magnitudes from 1e-12 to
// 1e12, near the octants' edges (the axes, the diagonals, tan(pi/8) where
// the reduction switches) and at tiny angles; the four-lane form gives the
// scalar one's numbers bit for bit; NaN stays NaN; signed zeros and the
// axes exact.
TEST(AngleKernel, WithinUlpsOfStdAtan2) {
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> u(-1, 1);
  const double pi = 3.141592653589793;
  double worst = 0;
  auto ulps = [](double mine, double ref) {
    const double ulp = std::nextafter(std::fabs(ref), INFINITY) - std::fabs(ref);
    return std::fabs(mine - ref) / ulp;
  };
  auto check = [&](const double y[4], const double x[4]) {
    double th[4];
    turn_atan2_four(y, x, th);
    for (int l = 0; l < 4; ++l) {
      const double one = turn_atan2(y[l], x[l]);
      ASSERT_EQ(std::memcmp(&one, &th[l], sizeof one), 0) << "lane " << l << ": " << y[l] << ", " << x[l];
      const double e = ulps(one, std::atan2(y[l], x[l]));
      worst = std::max(worst, e);
      ASSERT_LE(e, 2.0) << "atan2(" << y[l] << ", " << x[l] << ") = " << std::atan2(y[l], x[l]) << ", the kernels' "
                        << one;
    }
  };
  for (int sample = 0; sample < 200000; ++sample) {
    double y[4], x[4];
    for (int l = 0; l < 4; ++l) {
      const double r = std::pow(10.0, 12 * u(rng));
      double a = pi * u(rng);
      switch ((sample + l) % 5) {
        case 1: a = 0.25 * pi * std::round(4 * a / pi) + 1e-9 * u(rng); break;  // near an axis or a diagonal
        case 2: a = std::copysign(std::atan(0.41421356237309503), a) + 1e-12 * u(rng); break;  // the switch
        case 3: a = 1e-6 * u(rng) * std::pow(10.0, -8 * std::fabs(u(rng))); break;  // tiny
        default: break;
      }
      y[l] = r * std::sin(a);
      x[l] = r * std::cos(a);
    }
    check(y, x);
    if (HasFatalFailure()) return;
  }
  const double y[4] = {0.0, -0.0, 0.0, 1.0}, x[4] = {1.0, 1.0, -1.0, 0.0};
  double th[4];
  turn_atan2_four(y, x, th);
  EXPECT_EQ(std::memcmp(&th[0], &y[0], sizeof(double)), 0) << "atan2(+0, 1) is +0";
  EXPECT_EQ(std::memcmp(&th[1], &y[1], sizeof(double)), 0) << "atan2(-0, 1) is -0";
  EXPECT_EQ(th[2], pi);
  EXPECT_EQ(th[3], 0.5 * pi);
  EXPECT_EQ(turn_atan2(0.0, 0.0), 0.0);
  EXPECT_TRUE(std::isnan(turn_atan2(std::nan(""), 1.0)));
  EXPECT_TRUE(std::isnan(turn_atan2(1.0, std::nan(""))));
  EXPECT_GT(worst, 0.0) << "no sample differed from std::atan2: are both the same function?";
  std::printf("kernels' atan2: at most %.2f ulp from std::atan2\n", worst);
}

// Four edges side by side (edge_length_four, edge_length_hv_four) give each
// edge's scalar kernel numbers bit for bit: the length, the gradient and the
// Hessian along the ends' moves, four different edges at a time, short and
// long, stretched along any direction.
TEST(EdgeLanes, FourEdgesAreTheScalarKernelsBitForBit) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(-1, 1);
  auto same = [](const void* a, const void* b, size_t n) { return std::memcmp(a, b, n) == 0; };
  for (int sample = 0; sample < 2000; ++sample) {
    EdgeFour e;
    V3<double> v[4];
    for (int l = 0; l < 4; ++l) {
      const double h = (sample + l) % 2 ? 1e-3 : 3e-2, amount = (sample + l) % 3 == 0 ? 0.05 : 0.9;
      e.a[l] = {h * amount * u(rng), h * amount * u(rng), h * amount * u(rng)};
      e.b[l] = {h * (1 + amount * u(rng)), h * amount * u(rng), h * amount * u(rng)};
      v[l] = {u(rng), u(rng), u(rng)};
    }
    V3<double> g[4][2], gh[4][2], hv[4];
    double L[4], Lh[4];
    edge_length_four(e, g, L);
    edge_length_hv_four(e, v, gh, Lh, hv);
    for (int l = 0; l < 4; ++l) {
      V3<double> g1[2], gh1[2], hv1;
      const double L1 = edge_length(e.a[l], e.b[l], g1), Lh1 = edge_length_hv(e.a[l], e.b[l], v[l], gh1, hv1);
      ASSERT_TRUE(same(&L[l], &L1, sizeof L1) && same(&Lh[l], &Lh1, sizeof L1)) << "sample " << sample << " lane " << l;
      ASSERT_TRUE(same(g[l], g1, sizeof g1) && same(gh[l], gh1, sizeof g1) && same(gh1, g1, sizeof g1))
          << "sample " << sample << " lane " << l;
      ASSERT_TRUE(same(&hv[l], &hv1, sizeof hv1)) << "sample " << sample << " lane " << l;
    }
  }
}

#if DRAPE_LANES
// Band::stop and Band::excess in lanes (band_K.hpp) against the scalar ones,
// bit for bit: a linear band and a tensile one (power law, compression
// branch, past EMT), reversal 0 and 3, forces inside, outside, exactly on an
// edge (the stop's own case), a zero-width band and NaN; each lane from its
// own band, as a run's warp and weft elements alternate.
TEST(BandLanes, StopAndExcessAreTheScalarBandsBitForBit) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(-1, 1);
  auto same = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  Band bands[6] = {Band::linear(2e-5, 7e-4), Band::linear(3e-5, 0), Band::tensile(TensileKES{}, 0.5),
                   Band::linear(2e-5, 7e-4), Band::linear(3e-5, 0), Band::tensile(TensileKES{}, 0.5)};
  for (int k = 3; k < 6; ++k) bands[k].set_reversal(3.0);
  int on_edge = 0, outside = 0, inside = 0;
  for (int sample = 0; sample < 20000; ++sample) {
    BandValue v[4];
    double q[4], anchor[4], f[4], rev[4];
    const Band* b[4];
    for (int l = 0; l < 4; ++l) {
      b[l] = &bands[(sample + 5 * l) % 6];
      const bool tensile = (sample + 5 * l) % 3 == 2;
      q[l] = tensile ? 0.08 * u(rng) : 40 * u(rng);  // past EMT and into compression; curvatures
      v[l] = b[l]->at(q[l]);
      rev[l] = b[l]->reversal();
      const double width = v[l].hi - v[l].lo, scale = std::fabs(v[l].hi) + width + 1e-3;
      const int kind = (sample + l) % 5;
      // anchor: the stop's force f1 + rev hi lands at hi or lo exactly (0, 1),
      // or anywhere; f: on an edge (2), or anywhere.
      anchor[l] = kind == 0 ? v[l].hi - rev[l] * v[l].hi : kind == 1 ? v[l].lo - rev[l] * v[l].hi : 2 * scale * u(rng);
      f[l] = kind == 2 ? v[l].lo : kind == 3 && sample % 7 == 0 ? std::nan("") : v[l].lo + width * 1.5 * u(rng);
    }
    const BandFour v4 = band_four(v);
    const StopFour st = band_stop4(D4{anchor[0], anchor[1], anchor[2], anchor[3]}, D4{rev[0], rev[1], rev[2], rev[3]}, v4);
    const ExcessFour ex = band_excess4(D4{f[0], f[1], f[2], f[3]}, v4);
    for (int l = 0; l < 4; ++l) {
      const Band::Stop s1 = b[l]->stop(anchor[l], v[l]);
      const BandExcess e1 = Band::excess(f[l], v[l]);
      ASSERT_TRUE(same(st.f[l], s1.f) && same(st.df_dq[l], s1.df_dq)) << "sample " << sample << " lane " << l;
      ASSERT_TRUE(same(ex.r[l], e1.r) && same(ex.dr_dq[l], e1.dr_dq)) << "sample " << sample << " lane " << l;
      const double f1 = anchor[l] + rev[l] * v[l].hi;
      on_edge += rev[l] > 0 && (f1 == v[l].hi || f1 == v[l].lo) && v[l].lo < v[l].hi;
      outside += e1.r != 0;
      inside += e1.r == 0 && f[l] == f[l];
    }
  }
  // Every case was met, many times.
  EXPECT_GT(on_edge, 1000);
  EXPECT_GT(outside, 10000);
  EXPECT_GT(inside, 10000);
}

// Four tensile power-law bands in the lanes (tensile_band4, two directions'
// numbers mixed across the lanes) against Band::at: compression's line and
// onset, the power law, past EMT, their boundaries and a NaN, bit for bit.
TEST(BandLanes, TensileBandsAreBandAtBitForBit) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  auto same = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  TensileKES warp, weft;
  weft.emt = 0.03, weft.lt = 0.55, weft.rt = 0.4, weft.fm = 300;
  const Band bands[2] = {Band::tensile(warp, 0.5), Band::tensile(weft, 2.0)};
  const Band::PowerLaw law[2] = {bands[0].power_law_terms(), bands[1].power_law_terms()};
  ASSERT_TRUE(bands[0].power_law() && bands[1].power_law());
  int branch[3] = {0, 0, 0};  // compression, power law, past EMT
  for (int sample = 0; sample < 20000; ++sample) {
    double q[4];
    const Band::PowerLaw* p[4];
    int d[4];
    for (int l = 0; l < 4; ++l) {
      d[l] = int((sample >> l) & 1);
      const double emt = law[d[l]].emt;
      const int kind = (sample + 3 * l) % 11;
      // Exactly on a branch's boundary (0, EMT, -eps), a NaN, or anywhere in [-2 EMT, 2 EMT].
      q[l] = kind == 0 ? 0.0 : kind == 1 ? emt : kind == 2 ? -Band::kCompressionOnset * emt
             : kind == 3 && sample % 13 == 0 ? std::nan("") : 2 * emt * u(rng);
      p[l] = &law[d[l]];
      branch[q[l] <= 0 ? 0 : q[l] < emt ? 1 : 2] += q[l] == q[l];
    }
    const BandFour v4 = tensile_band4(D4{q[0], q[1], q[2], q[3]}, p);
    for (int l = 0; l < 4; ++l) {
      const BandValue v = bands[d[l]].at(q[l]);
      ASSERT_TRUE(same(v4.lo[l], v.lo) && same(v4.hi[l], v.hi) && same(v4.dlo[l], v.dlo) && same(v4.dhi[l], v.dhi))
          << "sample " << sample << " lane " << l << " q " << q[l];
    }
  }
  for (int b : branch) EXPECT_GT(b, 10000);
}

// Four linear bands in the lanes (linear_band4, two bands' numbers mixed)
// against Band::at, bit for bit.
TEST(BandLanes, LinearBandsAreBandAtBitForBit) {
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(-1, 1);
  auto same = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  const Band bands[2] = {Band::linear(2e-5, 7e-4), Band::linear(3.3e-5, 1.1e-4)};
  ASSERT_TRUE(bands[0].plain_linear() && bands[1].plain_linear());
  ASSERT_FALSE(Band::tensile(TensileKES{}).plain_linear());
  for (int sample = 0; sample < 5000; ++sample) {
    double q[4];
    int d[4];
    for (int l = 0; l < 4; ++l) d[l] = int((sample >> l) & 1), q[l] = 40 * u(rng);
    const BandFour v4 = linear_band4(D4{q[0], q[1], q[2], q[3]},
                                     D4{bands[d[0]].slope(), bands[d[1]].slope(), bands[d[2]].slope(), bands[d[3]].slope()},
                                     D4{bands[d[0]].half_width(), bands[d[1]].half_width(), bands[d[2]].half_width(),
                                        bands[d[3]].half_width()});
    for (int l = 0; l < 4; ++l) {
      const BandValue v = bands[d[l]].at(q[l]);
      ASSERT_TRUE(same(v4.lo[l], v.lo) && same(v4.hi[l], v.hi) && same(v4.dlo[l], v.dlo) && same(v4.dhi[l], v.dhi))
          << "sample " << sample << " lane " << l;
    }
  }
}
#endif

// A run-taking loop body (ItemRun) sees every item once, in fours and then
// one by one, whatever the run's length and start.
TEST(TripleLanes, InFoursVisitsEachItemOnce) {
  for (int64_t begin = 0; begin < 5; ++begin)
    for (int64_t len = 0; len < 11; ++len) {
      std::vector<int> seen(size_t(begin + len), 0);
      int fours = 0;
      in_fours(ItemRun{nullptr, begin, begin + len, 0},
               [&](int64_t k) {
                 ++fours;
                 for (int l = 0; l < 4; ++l) ++seen[size_t(k + l)];
               },
               [&](int64_t k) { ++seen[size_t(k)]; });
      EXPECT_EQ(fours, len / 4) << "begin " << begin << " length " << len;
      for (int64_t k = 0; k < begin + len; ++k) EXPECT_EQ(seen[size_t(k)], k >= begin ? 1 : 0) << "item " << k;
    }
}

// Newton's K (Evaluator::stiffness_product, matrix-free, its element passes
// and particle gather in one parallel region) on random states with forces
// at their hysteresis targets, plain and AMRC mesh: symmetric, positive
// definite, zero off the free particles' positions, and its diagonal
// estimate (stiffness_diagonal) positive where K's is.
TEST(Stiffness, SymmetricPositiveDefiniteOnTheFreePositions) {
  for (bool amrc : {false, true})
  for (bool friction : {false, true}) {
    const auto world = random_world(11, amrc);
    Simulation& w = *world;
    if (friction) {
      ASSERT_GT(with_friction(w), 0);
    }
    Evaluator& ev = w.loop->evaluator();
    ev.hysteresis_forces(w.cloth.z.data());
    ev.evaluate(w.cloth.z.data(), nullptr);
    const size_t n = w.cloth.z.size();
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<double> a(n, 0.0), b(n, 0.0), ka(n, -7.0), kb(n, -7.0), diag(n, 0.0);
    std::vector<char> on(n, 0);
    for (int64_t p : w.lists.particles.items)
      for (int k = 0; k < 3; ++k) {
        on[3 * p + k] = 1;
        a[3 * p + k] = u(rng);
        b[3 * p + k] = u(rng);
      }
    ev.stiffness_diagonal(w.cloth.z.data(), diag.data());  // first: it freezes the band slopes
    ev.stiffness_product(w.cloth.z.data(), a.data(), ka.data());
    ev.stiffness_product(w.cloth.z.data(), b.data(), kb.data());
    double bka = 0, akb = 0, aka = 0, scale = 0;
    for (size_t k = 0; k < n; ++k) {
      if (!on[k]) continue;
      bka += b[k] * ka[k];
      akb += a[k] * kb[k];
      aka += a[k] * ka[k];
      scale += std::fabs(b[k] * ka[k]);
      EXPECT_GT(diag[k], 0.0) << "entry " << k << (amrc ? " (AMRC)" : "");
    }
    EXPECT_NEAR(bka, akb, 1e-12 * scale) << (amrc ? "AMRC mesh" : "plain mesh");
    EXPECT_GT(aka, 0.0) << (amrc ? "AMRC mesh" : "plain mesh");
    // Entries that are not free positions are left alone (Newton's vectors
    // never read them): the -7 written above survives.
    for (size_t k = 0; k < size_t(w.cloth.layout.tension()); ++k)
      if (!on[k] && !(w.cloth.flags[k / 3] & kHanging)) {
        EXPECT_EQ(ka[k], -7.0) << "entry " << k;
      }
  }
}

// K assembled (Evaluator::assemble_stiffness, the multigrid's finest
// level) is the matrix-free product's operator: A v equals K v on the free
// particles to rounding, on the plain and the AMRC mesh (hanging particles
// folded onto their ends), and A is symmetric block by block.
TEST(Stiffness, AssembledMatchesTheProduct) {
  for (bool amrc : {false, true})
  for (bool friction : {false, true}) {
    const auto world = random_world(13, amrc);
    Simulation& w = *world;
    if (friction) {
      ASSERT_GT(with_friction(w), 0);
    }
    w.loop->evaluator().settled_cost(w.cloth.z.data());
    std::vector<double> diag;
    expect_assembled_is_the_product(w, std::string(amrc ? "AMRC" : "plain") + (friction ? ", friction" : ""), diag);
  }
}

// K against central differences of the Newton residual it linearises
// (forces at their hysteresis targets, settled_cost). K leaves out the
// bending and shear geometric terms (force x the strain's second
// derivative) and the contact normal's curvature: on a flat cloth whose
// bands have no width (bending and shear forces zero there), stretched in
// its plane (tension: the stretch geometric term counts) and pressed into
// the floor (a flat obstacle), the left-out terms vanish and K must be the
// residual's whole derivative. Plain and AMRC mesh.
TEST(Stiffness, MatchesFiniteDifferencesOfTheResidual) {
  for (bool amrc : {false, true})
  for (bool friction : {false, true}) {
    Scene s = flat_scene(13, 11, 0.12, 0.10);
    s.obstacle.floor = true;
    s.solver.dt = 2e-3;
    Fabric f = test_fabric();
    for (int d = 0; d < 2; ++d) f.bending[d].hb = 0;
    f.shear.hg = 0;
    Simulation w(s, f);
    if (amrc) w.set_tree(amrc_tree());
    w.cloth.flags[0] |= kFixed;
    w.rebuild();
    // A tilted plane, stretched in it (tension), its lower part inside the
    // floor's contact layer (half a spacing): flat and unsheared still.
    const double layer = 0.5 * w.cloth.grid.hi;
    for (int64_t p = 0; p < w.cloth.grid.n(); ++p) {
      for (int k = 0; k < 2; ++k) w.cloth.z[3 * p + k] *= 1.02;
      w.cloth.z[3 * p + 2] = 0.5 * layer + 0.3 * (w.cloth.z[3 * p] - w.cloth.z[0]) * 0.1;
    }
    // Friction: the step started at z less a slip along the floor of up to
    // twice the ramp, so that the particles the floor held then slide, some
    // on the ramp, some beyond.
    std::mt19937_64 slips(11);
    std::uniform_real_distribution<double> us(-1, 1);
    if (friction) {
      w.model.contact.floor_friction = 0.5;
      w.model.contact.slip = 1e-4;
      for (int64_t p = 0; p < w.cloth.grid.n(); ++p)
        for (int k = 0; k < 3; ++k) w.cloth.x1[3 * p + k] = w.cloth.z[3 * p + k] - (k < 2 ? 2e-4 * us(slips) : 0.0);
    }
    Evaluator& ev = w.loop->evaluator();
    const size_t n = w.cloth.z.size();
    std::vector<double> v(n, 0.0), kv(n, 0.0), diag(n, 0.0);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int64_t p : w.lists.particles.items)
      for (int k = 0; k < 3; ++k) v[3 * p + k] = u(rng);
    ev.settled_cost(w.cloth.z.data());
    ev.stiffness_diagonal(w.cloth.z.data(), diag.data());
    ev.stiffness_product(w.cloth.z.data(), v.data(), kv.data());
    // The residual at z +- eps v (F0 units; K maps positions in F0 units).
    const double eps = 1e-7 * w.cloth.grid.hi;
    auto residual_at = [&](double sign) {
      std::vector<double> z = w.cloth.z;
      for (int64_t p : w.lists.particles.items)
        for (int k = 0; k < 3; ++k) z[3 * p + k] += sign * eps * v[3 * p + k];
      ev.settled_cost(z.data());
      return ev.residual();
    };
    const std::vector<double> rp = residual_at(1), rm = residual_at(-1);
    const double F0 = ev.force_scale();
    double scale = 0;
    for (int64_t p : w.lists.particles.items)
      for (int k = 0; k < 3; ++k) scale = std::max(scale, std::fabs(kv[3 * p + k]));
    int touching = 0;
    for (int64_t p : w.lists.particles.items) touching += w.cloth.z[3 * p + 2] < layer;
    ASSERT_GT(touching, 0);
    ASSERT_LT(touching, int(w.lists.particles.size()));
    const std::vector<int64_t>& ids = w.lists.particles.items;
    for (size_t r = 0; r < ids.size(); ++r)  // the residual in list order
      for (int k = 0; k < 3; ++k) {
        const int64_t p = ids[r];
        const double fd = (rp[3 * r + k] - rm[3 * r + k]) / (2 * eps) * F0;
        EXPECT_NEAR(kv[3 * p + k], fd, 1e-5 * scale) << "particle " << p << " axis " << k << (amrc ? " (AMRC)" : "")
                                                     << (friction ? " friction" : "");
      }
  }
}

// stiffness_diagonal keeps the elements' z-only numbers (gradients, slope
// factors) at its z for the products: a product read back from them is bit
// for bit one that keeps nothing and computes them itself, twice in a row,
// and after z moves the products follow it (an evaluator that never saw the
// old z agrees exactly).
TEST(Stiffness, KeptGradientsFollowZ) {
  for (bool amrc : {false, true}) {
    const auto world = random_world(12, amrc);
    Simulation& w = *world;
    const auto fresh_world = random_world(12, amrc);
    Simulation& fresh = *fresh_world;
    const size_t n = w.cloth.z.size();
    std::vector<double> v(n, 0.0), k1(n), k2(n), k3(n), diag(n);
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int64_t p : w.lists.particles.items)
      for (int k = 0; k < 3; ++k) v[3 * p + k] = u(rng);
    auto product = [&](Simulation& x, std::vector<double>& out) {
      Evaluator& ev = x.loop->evaluator();
      ev.hysteresis_forces(x.cloth.z.data());
      ev.stiffness_diagonal(x.cloth.z.data(), diag.data());
      std::vector<double> vv = v;
      ev.stiffness_product(x.cloth.z.data(), vv.data(), out.data());
    };
    product(w, k1);
    std::vector<double> vv = v;
    w.loop->evaluator().stiffness_product(w.cloth.z.data(), vv.data(), k2.data());
    EXPECT_EQ(k1, k2) << (amrc ? "AMRC mesh" : "plain mesh");
    w.loop->evaluator().keep_products(false);  // computed anew each time: the same numbers
    product(w, k3);
    EXPECT_EQ(k1, k3) << (amrc ? "AMRC mesh, not keeping" : "plain mesh, not keeping");
    w.loop->evaluator().keep_products(true);
    for (Simulation* x : {&w, &fresh})
      for (int64_t p : x->lists.particles.items) x->cloth.z[3 * p + 2] += 1e-3 * x->cloth.grid.hi * (p % 5);
    product(w, k2);
    product(fresh, k3);
    EXPECT_EQ(k2, k3) << (amrc ? "AMRC mesh" : "plain mesh");
    EXPECT_NE(k1, k2) << "the move changed nothing: the test does not test";
  }
}

// Newton's cost pass (settled_cost: each element's force set to its
// hysteresis target and its cost terms in one pass) is bit for bit
// hysteresis_forces then evaluate; the numbers it keeps give bit for bit the
// same K diagonal and products as computing them at z again. Then z moves:
// the next settled_cost must renew every kept number (the elements' and the
// particles' contact ones) for an evaluator that never saw the old z.
TEST(Stiffness, SettledCostIsHysteresisForcesThenEvaluate) {
  for (bool amrc : {false, true}) {
    const auto two_world = random_world(14, amrc);
    Simulation& two = *two_world;
    const auto one_world = random_world(14, amrc);
    Simulation& one = *one_world;
    const size_t n = two.cloth.z.size();
    std::vector<double> v(n, 0.0);
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int64_t p : two.lists.particles.items)
      for (int k = 0; k < 3; ++k) v[3 * p + k] = u(rng);
    struct Out {
      CostTerms cost;
      std::vector<double> z, rho, diag, k1, k2;
    };
    auto run = [&](Simulation& w, bool settled) {
      Evaluator& ev = w.loop->evaluator();
      Out o;
      if (settled) {
        o.cost = ev.settled_cost(w.cloth.z.data());
        EXPECT_TRUE(ev.diagonal_reads_settled()) << "the fast path is not taken: the test does not test";
      } else {
        ev.hysteresis_forces(w.cloth.z.data());
        o.cost = ev.evaluate(w.cloth.z.data(), nullptr);
      }
      o.z = w.cloth.z;
      o.rho = ev.residual();
      o.diag.assign(n, 0.0);
      o.k1.assign(n, 0.0);
      o.k2.assign(n, 0.0);
      ev.stiffness_diagonal(w.cloth.z.data(), o.diag.data());
      std::vector<double> vv = v;
      ev.stiffness_product(w.cloth.z.data(), vv.data(), o.k1.data());
      ev.stiffness_product(w.cloth.z.data(), vv.data(), o.k2.data());
      return o;
    };
    const char* mesh = amrc ? "AMRC mesh" : "plain mesh";
    auto same = [&](const Out& a, const Out& b, const char* when) {
      EXPECT_EQ(a.cost.newton, b.cost.newton) << mesh << when;
      EXPECT_EQ(a.cost.stretch, b.cost.stretch) << mesh << when;
      EXPECT_EQ(a.cost.bend, b.cost.bend) << mesh << when;
      EXPECT_EQ(a.cost.shear, b.cost.shear) << mesh << when;
      EXPECT_EQ(a.z, b.z) << mesh << when << ": element forces";
      EXPECT_EQ(a.rho, b.rho) << mesh << when << ": residuals";
      EXPECT_EQ(a.diag, b.diag) << mesh << when << ": K's diagonal";
      EXPECT_EQ(a.k1, b.k1) << mesh << when << ": K v";
      EXPECT_EQ(a.k2, b.k2) << mesh << when << ": K v read back";
    };
    const Out first = run(two, false);
    same(first, run(one, true), "");
    for (Simulation* x : {&two, &one})
      for (int64_t p : x->lists.particles.items) {
        x->cloth.z[3 * p + 2] += 2e-3 * x->cloth.grid.hi * (p % 7);
        x->cloth.z[3 * p] -= 1e-3 * x->cloth.grid.hi * (p % 3);
      }
    const auto fresh_world = random_world(14, amrc);
    Simulation& fresh = *fresh_world;
    fresh.cloth.z = one.cloth.z;
    const Out moved = run(one, true);
    same(run(fresh, false), moved, ", z moved");
    EXPECT_NE(first.k1, moved.k1) << "the move changed nothing: the test does not test";
    EXPECT_NE(first.diag, moved.diag) << "the move changed nothing: the test does not test";
    // Whatever else reaches the evaluator between settled_cost and the
    // diagonal ends the shortcut: the diagonal then computes everything.
    Evaluator& ev = one.loop->evaluator();
    const std::function<void()> others[] = {
        [&] { ev.evaluate(one.cloth.z.data(), nullptr); },
        [&] { ev.hysteresis_forces(one.cloth.z.data()); },
        [&] { ev.hysteresis_anchors(one.cloth.x1.data(), one.cloth.z.data()); },
        [&] { ev.keep_products(true); }};
    for (const auto& other : others) {
      ev.settled_cost(one.cloth.z.data());
      other();
      EXPECT_FALSE(ev.diagonal_reads_settled()) << mesh;
    }
  }
}

// What one evaluation leaves: the cost terms, the gradient and the residuals
// in list order and at z's indices.
struct Evaluated {
  CostTerms cost;
  std::vector<double> grad, rho, rho_grid;
};

// w's z with each particle raised by `move` steps of a pattern.
std::vector<double> moved_z(const Simulation& w, int move) {
  std::vector<double> z = w.cloth.z;
  for (int64_t p : w.lists.particles.items) z[3 * p + 2] += 1e-3 * w.cloth.grid.hi * move * (p % 5);
  return z;
}

// The residuals the evaluator kept from its last evaluation, into o.
void read_residuals(Evaluator& ev, Evaluated& o) {
  o.rho = ev.residual();
  o.rho_grid = ev.gradient_residual();
}

// One evaluation of w at moved_z(w, move): the way under test with `tested`,
// the reference way without.
using Evaluation = std::function<Evaluated(Simulation& w, bool tested, int move)>;

// On a plain mesh and an AMRC one, on one thread and on three: two like
// worlds from `seed`, the reference evaluated on the first and the tested
// way on the second, each at z and then at z moved (what one evaluation left
// behind must not stand in for the next's), give the same numbers bit for
// bit, and the move changes the gradient. `then` checks the tested world
// afterwards.
void expect_tested_is_reference(unsigned seed, const Evaluation& run,
                                const std::function<void(Simulation&, const std::string& mesh)>& then = {}) {
  const int threads_before = omp_get_max_threads();
  for (bool amrc : {false, true})
    for (int threads : {1, 3}) {
      omp_set_num_threads(threads);
      const auto reference_world = random_world(seed, amrc), tested_world = random_world(seed, amrc);
      const std::string mesh = std::string(amrc ? "AMRC mesh, " : "plain mesh, ") + std::to_string(threads) + " threads";
      if (amrc) {
        ASSERT_GT(tested_world->lists.hanging.size(), 0u) << mesh << ": no hanging particles: the test does not test them";
      }
      std::vector<double> first;
      for (int move : {0, 1}) {
        const Evaluated reference = run(*reference_world, false, move), tested = run(*tested_world, true, move);
        const std::string where = mesh + (move ? ", z moved" : "");
        EXPECT_EQ(reference.cost.newton, tested.cost.newton) << where;
        EXPECT_EQ(reference.cost.stretch, tested.cost.stretch) << where;
        EXPECT_EQ(reference.cost.bend, tested.cost.bend) << where;
        EXPECT_EQ(reference.cost.shear, tested.cost.shear) << where;
        EXPECT_EQ(reference.grad, tested.grad) << where << ": the gradient";
        EXPECT_EQ(reference.rho, tested.rho) << where << ": the residuals";
        EXPECT_EQ(reference.rho_grid, tested.rho_grid) << where << ": the residuals at z's indices";
        if (move) {
          EXPECT_NE(first, tested.grad) << where << ": the move changed nothing: the test does not test";
        }
        first = tested.grad;
      }
      if (then) then(*tested_world, mesh);
    }
  omp_set_num_threads(threads_before);
}

// evaluate(z, grad) in one parallel region gives the separate regions'
// numbers bit for bit: the cost terms, the gradient (every entry: the fused
// one starts from NaN, so an entry it left unwritten would show), the
// residuals in list order and at z's indices; on a plain mesh and an AMRC
// one (hanging particles: their forces and residuals run on the master
// thread between the passes), on one thread and on three.
TEST(Evaluator, FusedCostGradientIsTheSeparatePasses) {
  expect_tested_is_reference(17, [](Simulation& w, bool fused, int move) {
    Evaluator& ev = w.loop->evaluator();
    ev.fuse_gradient(fused);
    std::vector<double> z = moved_z(w, move);
    Evaluated o;
    o.grad.assign(z.size(), fused ? std::nan("") : 0.0);
    o.cost = ev.evaluate(z.data(), o.grad.data());
    read_residuals(ev, o);
    return o;
  });
}

// The gradient and the scaling diagonal in the compact order (the nonlinear
// CG's) are the ones at z's indices, bit for bit, entry by entry: 3 per
// free particle in list order, then the owned edges', triples' and cells'
// forces in list order. Every compact entry starts NaN (one left unwritten
// would show); fused and separate passes, cost then gradient, on a plain
// mesh and an AMRC one (hanging particles pass their terms to their ends).
TEST(Evaluator, CompactGradientIsTheGridOne) {
  for (bool amrc : {false, true})
    for (bool fused : {true, false}) {
      const auto w = random_world(23, amrc);
      Evaluator& ev = w->loop->evaluator();
      ev.fuse_gradient(fused);
      const std::string mesh = std::string(amrc ? "AMRC mesh" : "plain mesh") + (fused ? ", fused" : ", separate");
      if (amrc) {
        ASSERT_GT(w->lists.hanging.size(), 0u) << mesh << ": no hanging particles: the test does not test them";
      }
      const Layout& L = w->cloth.layout;
      std::vector<int64_t> at;  // compact entry -> z index
      for (int64_t p : w->lists.particles.items)
        for (int k = 0; k < 3; ++k) at.push_back(3 * p + k);
      for (int64_t s : w->lists.edges.items) at.push_back(L.tension() + s);
      for (int64_t s : w->lists.triples.items) at.push_back(L.moment() + s);
      for (int64_t s : w->lists.shears.items) at.push_back(L.shear() + s);
      ASSERT_EQ(int64_t(at.size()), ev.compact_size()) << mesh;
      std::vector<double> z = w->cloth.z;
      for (int64_t p : w->lists.particles.items) z[3 * p + 2] += 1e-3 * w->cloth.grid.hi * (p % 5);
      std::vector<double> grid(z.size(), 0.0), compact(at.size(), std::nan(""));
      std::vector<double> dgrid(z.size(), 0.0), dcompact(at.size(), std::nan(""));
      const CostTerms cg = ev.evaluate(z.data(), grid.data());
      const CostTerms cc = ev.evaluate_compact(z.data(), compact.data());
      EXPECT_EQ(cg.total(), cc.total()) << mesh;
      ev.scaling_diagonal(z.data(), dgrid.data());
      ev.scaling_diagonal_compact(z.data(), dcompact.data());
      std::vector<double> split(at.size(), std::nan(""));
      ev.cost_for_gradient(z.data());
      ev.gradient_at_last_cost_compact(split.data());
      int nonzero = 0;
      for (size_t c = 0; c < at.size(); ++c) {
        ASSERT_EQ(grid[at[c]], compact[c]) << mesh << ": gradient entry " << c << " (z index " << at[c] << ")";
        ASSERT_EQ(grid[at[c]], split[c]) << mesh << ": cost then gradient, entry " << c;
        ASSERT_EQ(dgrid[at[c]], dcompact[c]) << mesh << ": diagonal entry " << c;
        nonzero += grid[at[c]] != 0.0;
      }
      EXPECT_GT(nonzero, int(at.size()) / 2) << mesh << ": a zero gradient tests nothing";
    }
}

// cost_for_gradient(z) then gradient_at_last_cost(grad) gives what
// evaluate(z, grad) in one parallel region gives, bit for bit: the cost
// terms, every gradient entry (both start from NaN), the residuals; on a
// plain mesh and an AMRC one, on one thread and on three; at z and at z
// moved, the pair's evaluator costing a trial at another z before each (the
// line search's rejected trials: their numbers must not stand in).
TEST(Evaluator, CostThenGradientIsEvaluate) {
  const Evaluation run = [](Simulation& w, bool split, int move) {
    Evaluator& ev = w.loop->evaluator();
    std::vector<double> z = moved_z(w, move);
    Evaluated o;
    o.grad.assign(z.size(), std::nan(""));
    if (split) {
      std::vector<double> rejected = moved_z(w, move + 3);
      ev.cost_for_gradient(rejected.data());
      o.cost = ev.cost_for_gradient(z.data());
      ev.gradient_at_last_cost(o.grad.data());
    } else {
      o.cost = ev.evaluate(z.data(), o.grad.data());
    }
    read_residuals(ev, o);
    return o;
  };
  // The gradient is taken once per cost: a second one has nothing to read.
  expect_tested_is_reference(19, run, [](Simulation& split, const std::string& mesh) {
    std::vector<double> g(split.cloth.z.size());
    EXPECT_THROW(split.loop->evaluator().gradient_at_last_cost(g.data()), std::logic_error) << mesh;
  });
}

// The element buffers are kept in list order (the ring's after this rank's),
// each particle reading its entries from a row built from the lists, and the
// elements their neighbours from list-ordered copies: when the mesh changes
// under an evaluator, as the drape program does between steps, every entry
// point must notice it on its own. After each change, the entry point called
// first gives bit for bit what an evaluator built on the new mesh gives. The
// changes alternate: a refine (new particles, elements and hanging ones) and
// a fixed particle (the particle list changes, the hanging ones do not, so
// only the lists' stamp tells). settled_cost comes right before the
// diagonal: a diagonal first after a change must not read its numbers.
TEST(Evaluator, FollowsItsListsAcrossMeshChanges) {
  const auto world = random_world(21, true);
  Simulation& w = *world;
  Evaluator& ev = w.loop->evaluator();
  const size_t n = w.cloth.z.size();
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> v(n);
  for (double& x : v) x = u(rng);
  std::vector<int> owned(w.tiling.count());
  for (int t = 0; t < w.tiling.count(); ++t) owned[t] = t;
  auto change = [&](bool refine) {
    const int64_t before = w.lists.particles.size();
    const size_t hanging = w.lists.hanging.size();
    if (refine) {
      std::vector<Cell> leaves;
      w.tree()->leaves(leaves);
      const auto coarse = std::find_if(leaves.begin(), leaves.end(), [](const Cell& c) { return c.level > 0; });
      ASSERT_NE(coarse, leaves.end()) << "no leaf left to refine";
      Quadtree finer = *w.tree();
      finer.refine(*coarse);
      w.amrc->restore(finer.levels());
      w.amrc->apply(w.cloth, w.fabric.density, w.scene.cloth.shear);
    } else {
      w.cloth.flags[w.lists.particles.items[w.lists.particles.size() / 2]] |= kFixed;
    }
    build_active_lists(w.cloth, w.tiling, owned, w.lists);
    hanging_links(*w.tree(), w.lists.hanging);
    w.loop->freeze_bend_axes();  // new triples' axes
    ASSERT_NE(w.lists.particles.size(), before) << "the lists did not change: the test does not test";
    if (!refine) {
      ASSERT_EQ(w.lists.hanging.size(), hanging);
    }
  };
  using Call = std::function<std::vector<double>(Evaluator&)>;
  const std::pair<const char*, Call> entries[] = {
      {"hysteresis_anchors",
       [&](Evaluator& e) {
         e.hysteresis_anchors(w.cloth.x1.data(), w.cloth.z.data());
         std::vector<double> a;  // by slot, the lists' order
         const ActiveList* lists[3] = {&w.lists.edges, &w.lists.triples, &w.lists.shears};
         for (int kind = 0; kind < 3; ++kind)
           for (int64_t s : lists[kind]->items) a.push_back(e.anchor(kind, s));
         return a;
       }},
      {"hysteresis_forces",
       [&](Evaluator& e) {
         std::vector<double> z = w.cloth.z;
         e.hysteresis_forces(z.data());
         return z;
       }},
      {"scaling_diagonal",
       [&](Evaluator& e) {
         std::vector<double> z = w.cloth.z, d(n, 0.0);
         e.scaling_diagonal(z.data(), d.data());
         return d;
       }},
      {"settled_cost, then stiffness_diagonal and stiffness_product",
       [&](Evaluator& e) {
         std::vector<double> z = w.cloth.z, d(n, 0.0), kv(n, 0.0), vv = v;
         const double cost = e.settled_cost(z.data()).total();
         e.stiffness_diagonal(z.data(), d.data());
         e.stiffness_product(z.data(), vv.data(), kv.data());
         z.insert(z.end(), d.begin(), d.end());
         z.insert(z.end(), kv.begin(), kv.end());
         z.push_back(cost);
         return z;
       }},
      {"stiffness_diagonal, then stiffness_product",
       [&](Evaluator& e) {
         std::vector<double> z = w.cloth.z, d(n, 0.0), kv(n, 0.0), vv = v;
         e.stiffness_diagonal(z.data(), d.data());
         e.stiffness_product(z.data(), vv.data(), kv.data());
         d.insert(d.end(), kv.begin(), kv.end());
         return d;
       }},
      {"evaluate",
       [&](Evaluator& e) {
         std::vector<double> z = w.cloth.z, g(n, 0.0);
         const double cost = e.evaluate(z.data(), g.data()).total();
         g.push_back(cost);
         return g;
       }},
  };
  for (const auto& entry : entries) entry.second(ev);  // rows for the first mesh
  bool refine = true;
  for (const auto& entry : entries) {
    change(refine);
    if (HasFatalFailure()) return;
    Evaluator fresh(w.cloth, w.model, w.lists, w.tiling, w.policy, w.red());
    const std::vector<double> mine = entry.second(ev), theirs = entry.second(fresh);
    EXPECT_EQ(mine, theirs) << entry.first << " first after " << (refine ? "a refine" : "fixing a particle");
    refine = !refine;
  }
}

// A triple's and a cell's kept gradients are, bit for bit, the ones a product
// that keeps nothing computes from z: kept by settled_cost's pass (the
// four-lane kernels) and by a diagonal at a z no settled_cost saw (the
// scalar ones), on a plain and an AMRC mesh. Bit for bit, not near: a
// product's K v can absorb a last-bit difference in a gradient that a long
// run's checksum would not.
TEST(Stiffness, KeptGradientsAreZsBitForBit) {
  for (bool amrc : {false, true}) {
    const auto world = random_world(15, amrc);
    Simulation& w = *world;
    Evaluator& ev = w.loop->evaluator();
    std::vector<double> diag(w.cloth.z.size());
    const char* mesh = amrc ? "AMRC mesh" : "plain mesh";
    auto same = [&](const char* when) {
      const double* z = w.cloth.z.data();
      int64_t checked = 0;
      for (int kind : {1, 2}) {
        const ActiveList& own = kind == 1 ? w.lists.triples : w.lists.shears;
        const ActiveList& ring = kind == 1 ? w.lists.ring_triples : w.lists.ring_shears;
        const int n = kind == 1 ? 3 : 4;
        for (int64_t pos = 0; pos < own.size() + ring.size(); ++pos) {
          V3<double> computed[4], kept[4];
          ev.element_gradients(kind, pos, z, computed, kept);
          for (int k = 0; k < n; ++k, ++checked) {
            EXPECT_EQ(computed[k].x, kept[k].x) << mesh << when << " kind " << kind << " at " << pos << " part " << k;
            EXPECT_EQ(computed[k].y, kept[k].y) << mesh << when << " kind " << kind << " at " << pos << " part " << k;
            EXPECT_EQ(computed[k].z, kept[k].z) << mesh << when << " kind " << kind << " at " << pos << " part " << k;
          }
        }
      }
      EXPECT_GT(checked, 100) << mesh << when << ": no elements: the test does not test";
    };
    ev.settled_cost(w.cloth.z.data());
    ev.stiffness_diagonal(w.cloth.z.data(), diag.data());
    same(", settled_cost's");
    for (int64_t p : w.lists.particles.items) w.cloth.z[3 * p + 2] += 1e-3 * w.cloth.grid.hi * (p % 5);
    ev.hysteresis_forces(w.cloth.z.data());
    ev.stiffness_diagonal(w.cloth.z.data(), diag.data());
    EXPECT_FALSE(ev.diagonal_reads_settled()) << mesh << ": the diagonal's own pass is not taken";
    same(", the diagonal's");
  }
}

// Newton's runs hold one number a triple and a cell in the element buffers
// (the particles multiply it by the kept gradients): the residual, K's
// diagonal and K v are the wide buffers' bit for bit. The same world
// before and after an entry point that widens them for good (the scaling
// diagonal's).
TEST(Stiffness, NarrowBuffersAreTheWideOnes) {
  for (bool amrc : {false, true}) {
    const auto world = random_world(13, amrc);
    Simulation& w = *world;
    Evaluator& ev = w.loop->evaluator();
    const size_t n = w.cloth.z.size();
    std::vector<double> v(n, 0.0), scale(n);
    std::mt19937_64 rng(4);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int64_t p : w.lists.particles.items)
      for (int k = 0; k < 3; ++k) v[3 * p + k] = u(rng);
    struct Parts {
      std::vector<double> residual, diag, kv;
      size_t buffers = 0;
    };
    auto parts = [&] {
      Parts o;
      o.diag.assign(n, 0.0);
      o.kv.assign(n, 0.0);
      ev.settled_cost(w.cloth.z.data());
      o.residual = ev.residual();
      ev.stiffness_diagonal(w.cloth.z.data(), o.diag.data());
      std::vector<double> vv = v;
      ev.stiffness_product(w.cloth.z.data(), vv.data(), o.kv.data());
      MemoryTable t;
      ev.memory(t);
      o.buffers = row_bytes(t, "Evaluator: element buffers (edges, triples, cells)");
      return o;
    };
    const Parts narrow = parts();
    ev.scaling_diagonal(w.cloth.z.data(), scale.data());
    const Parts wide = parts();
    const char* mesh = amrc ? "AMRC mesh" : "plain mesh";
    EXPECT_GT(wide.buffers, 2 * narrow.buffers) << mesh << ": the buffers did not widen";
    EXPECT_EQ(narrow.residual, wide.residual) << mesh;
    EXPECT_EQ(narrow.diag, wide.diag) << mesh;
    EXPECT_EQ(narrow.kv, wide.kv) << mesh;
    EXPECT_NE(narrow.kv, std::vector<double>(n, 0.0)) << mesh << ": no product: the test does not test";
  }
}

}  // namespace
}  // namespace drape::test
