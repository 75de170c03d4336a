// The Cusick drape test's parts: the disc obstacle's distance (its normal
// and curvature against central differences), the circular specimen cut
// from the grid (no element touches a removed particle, and the mass is the
// kept cells'), and the drape coefficient on shapes whose value is known.
#include <gtest/gtest.h>

#include <cmath>

#include "solver/contact.hpp"
#include "solver/drape_coefficient.hpp"
#include "solver/model.hpp"
#include "support/scenes.hpp"

using namespace drape;
using drape::test::test_fabric;

namespace {

Obstacle support_disc() {
  Obstacle o;
  o.shape = ObstacleShape::Disc;
  o.center[0] = 0.01;
  o.center[1] = -0.02;
  o.center[2] = 0.195;
  o.half[2] = 0.005;
  o.radius = 0.09;
  return o;
}

// A 0.3 m specimen cut to a disc over the 18 cm support disc.
Scene cusick_scene(int n) {
  Scene s;
  s.cloth.particles = {n, n};
  s.cloth.size = {0.3, 0.3};
  s.cloth.shape = ClothShape::Disc;
  s.cloth.tile = 16;
  s.cloth.height = 0.205;
  s.obstacle.shape = ObstacleShape::Disc;
  s.obstacle.center = {0.0, 0.0, 0.195};
  s.obstacle.size = {0.18, 0.18, 0.01};
  s.obstacle.radius = 0.09;
  s.amrc.start_spacing = 0;
  return s;
}

// The overhang beyond the disc's rim folded down so that its projection
// reaches `share` of the way out: the shadow is then a ring of known width.
// With waves > 0 the share swings by 0.35 about it, `waves` times around:
// an outline of that many nodes.
void fold_overhang(Cloth& c, double r_disc, double share, int waves = 0) {
  for (int64_t p = 0; p < c.grid.n(); ++p) {
    double* x = c.x() + 3 * p;
    const double rho = std::hypot(x[0], x[1]);
    if (rho <= r_disc) continue;
    const double s = waves > 0 ? share + 0.35 * std::cos(waves * std::atan2(x[1], x[0])) : share;
    const double out = r_disc + s * (rho - r_disc);
    x[2] -= std::sqrt(std::max(0.0, (rho - r_disc) * (rho - r_disc) - (out - r_disc) * (out - r_disc)));
    x[0] *= out / rho;
    x[1] *= out / rho;
  }
}

}  // namespace

// The gradient is the outward normal and the Hessian the normal's
// derivative: both against central differences off the top, the bottom,
// the rim and the round edge between them, and the flat faces inside.
TEST(ContactDisc, DistanceNormalAndCurvatureMatchDifferences) {
  const Obstacle o = support_disc();
  const double points[][3] = {
      {0.05, 0.03, 0.203},    // above the top
      {0.02, -0.01, 0.186},   // below the bottom
      {0.11, -0.02, 0.196},   // beside the rim
      {-0.06, 0.07, 0.197},   // beside the rim, another side
      {0.105, 0.01, 0.204},   // off the top edge (rim and top both)
      {-0.09, -0.06, 0.187},  // off the bottom edge
      {0.03, 0.0, 0.198},     // inside, nearest the top
      {0.097, -0.02, 0.1955},  // inside, nearest the rim
  };
  const double e = 1e-6;
  for (const auto& x : points) {
    SCOPED_TRACE(::testing::Message() << x[0] << ", " << x[1] << ", " << x[2]);
    double n[3], hess[9];
    disc_distance(o, x, n, hess);
    for (int k = 0; k < 3; ++k) {
      double xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]}, np[3], nm[3];
      xp[k] += e;
      xm[k] -= e;
      const double dp = disc_distance(o, xp, np, nullptr), dm = disc_distance(o, xm, nm, nullptr);
      EXPECT_NEAR((dp - dm) / (2 * e), n[k], 1e-6) << "normal " << k;
      for (int a = 0; a < 3; ++a) EXPECT_NEAR((np[a] - nm[a]) / (2 * e), hess[3 * a + k], 1e-4) << a << k;
    }
  }
}

TEST(ContactDisc, SignedDistanceOfKnownPoints) {
  const Obstacle o = support_disc();
  double n[3];
  const double above[3] = {0.01, -0.02, 0.21};
  EXPECT_NEAR(disc_distance(o, above, n, nullptr), 0.01, 1e-15);
  EXPECT_EQ(n[2], 1.0);
  const double beside[3] = {0.01 + 0.1, -0.02, 0.195};
  EXPECT_NEAR(disc_distance(o, beside, n, nullptr), 0.01, 1e-15);
  EXPECT_NEAR(n[0], 1.0, 1e-15);
  const double corner[3] = {0.01 + 0.093, -0.02, 0.204};  // 3 mm out, 4 mm up from the top edge
  EXPECT_NEAR(disc_distance(o, corner, n, nullptr), 0.005, 1e-15);
  const double inside[3] = {0.01, -0.02, 0.199};
  EXPECT_NEAR(disc_distance(o, inside, n, nullptr), -0.001, 1e-15);
  EXPECT_EQ(n[2], 1.0);
}

// A particle resting on the disc's top with friction is held there: the
// disc lends it a hold as the box does (a slip across the top is resisted).
TEST(ContactDisc, FrictionHoldsOnTheTop) {
  Contact c;
  c.obstacle = support_disc();
  c.thickness = 2e-3;
  c.stiffness = 10;
  c.friction = 0.5;
  const double x1[3] = {0.0, 0.0, 0.2 + 1e-3}, x[3] = {1e-4, 0.0, 0.2 + 1e-3};
  double f[3] = {0, 0, 0};
  friction_force(c, x, x1, f);
  EXPECT_LT(f[0], 0.0) << "friction opposes the slip";
  EXPECT_EQ(f[2], 0.0);
}

TEST(DiscCloth, NoElementTouchesARemovedParticle) {
  const Scene s = cusick_scene(33);
  const Cloth c = make_cloth(s, test_fabric());
  const Grid& g = c.grid;
  int64_t removed = 0, cells = 0;
  auto ok = [&](int64_t p) { return p >= 0 && c.active(p) && !(c.flags[p] & kRemoved); };
  for (int64_t p = 0; p < g.n(); ++p) {
    removed += (c.flags[p] & kRemoved) != 0;
    if (c.flags[p] & kRemoved) {
      EXPECT_FALSE(c.active(p));
      EXPECT_EQ(c.mass_at(p), 0.0);
    }
    for (int d = 0; d < 2; ++d) {
      EXPECT_TRUE(!c.edge_on[2 * p + d] || (ok(p) && ok(c.next_at(d, p)))) << p;
      EXPECT_TRUE(!c.triple_on[2 * p + d] || (ok(p) && ok(c.next_at(d, p)) && ok(c.prev_at(d, p)))) << p;
    }
    if (c.shear_on[p]) {
      ++cells;
      for (int k = 0; k < 3; ++k) EXPECT_TRUE(ok(c.cell[k][p])) << p;
    }
  }
  // The corners go; the circle's cells stay.
  EXPECT_GT(removed, 4 * 33);
  EXPECT_FALSE(c.flags[g.id(0, 0)] & kActive);
  EXPECT_TRUE(c.active(g.id(16, 16)));
  // The mass is the kept cells' area (each a shear cell) times the density.
  EXPECT_NEAR(c.total_mass(), test_fabric().density * cells * g.hi * g.hj, 1e-12 * c.total_mass());
  EXPECT_NEAR(cells * g.hi * g.hj, M_PI * 0.15 * 0.15, 0.01 * M_PI * 0.15 * 0.15);
}

TEST(DrapeCoefficient, FlatSpecimenReadsOne) {
  const Scene s = cusick_scene(65);
  const Cloth c = make_cloth(s, test_fabric());
  const DrapeTest t = drape_test(c, c.x(), s);
  EXPECT_EQ(t.coefficient, 1.0);
  EXPECT_NEAR(t.disc, M_PI * 0.09 * 0.09, 1e-3 * t.disc);
  EXPECT_NEAR(t.specimen, M_PI * 0.15 * 0.15, 0.005 * t.specimen);
  EXPECT_EQ(t.nodes, 0) << "a flat specimen has no folds";
}

TEST(DrapeCoefficient, HangingStraightDownReadsZero) {
  const Scene s = cusick_scene(65);
  Cloth c = make_cloth(s, test_fabric());
  fold_overhang(c, 0.09, 0.0);
  const DrapeTest t = drape_test(c, c.x(), s);
  EXPECT_NEAR(t.coefficient, 0.0, 0.005);
  EXPECT_GE(t.shadow, t.disc);
  EXPECT_EQ(t.nodes, 0);
}

// Folded down to reach halfway out: a ring from 9 to 12 cm (of 9 to 15).
TEST(DrapeCoefficient, HalfwayOutReadsTheRingsShare) {
  const Scene s = cusick_scene(129);
  Cloth c = make_cloth(s, test_fabric());
  fold_overhang(c, 0.09, 0.5);
  const DrapeTest t = drape_test(c, c.x(), s);
  const double ring = (0.12 * 0.12 - 0.09 * 0.09) / (0.15 * 0.15 - 0.09 * 0.09);
  EXPECT_NEAR(t.coefficient, ring, 0.02);
}

// An outline that swings out and back 4, 6 and 9 times around.
TEST(DrapeCoefficient, CountsTheNodesOfTheOutline) {
  const Scene s = cusick_scene(129);
  for (int waves : {4, 6, 9}) {
    Cloth c = make_cloth(s, test_fabric());
    fold_overhang(c, 0.09, 0.5, waves);
    EXPECT_EQ(drape_test(c, c.x(), s).nodes, waves);
  }
}
