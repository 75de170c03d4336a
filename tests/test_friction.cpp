// Coulomb friction against the floor: a cloth resting on a plane tilted by
// theta (gravity tilted instead) sticks when mu > tan(theta) and slides with
// acceleration g (sin(theta) - mu cos(theta)) when mu < tan(theta).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "support/scenes.hpp"

namespace drape::test {
namespace {

constexpr double kG = 9.80665;
constexpr double kTheta = 20 * M_PI / 180;  // tan = 0.364

// A 5 x 5 cloth lying in the floor's contact layer, friction mu on the
// floor, settled under upright gravity; a fixed step, so that positions are
// samples of one trajectory.
std::unique_ptr<Simulation> resting_cloth(double mu) {
  Scene s = flat_scene(5, 5, 0.04, 0.04);
  s.obstacle.floor = true;
  s.obstacle.floor_friction = mu;
  s.cloth.height = 0.99 * 0.005;  // the layer is half the 10 mm spacing; the penalty holds a weight 1 % in
  s.solver.dt = 1e-3;
  s.solver.dt_max = 1e-3;
  s.solver.tolerance = 1e-12;
  s.solver.max_iterations = 1000;
  auto w = std::make_unique<Simulation>(s, test_fabric());
  w->advance(50);
  return w;
}

void tilt(Simulation& w) {
  w.model.gravity[0] = kG * std::sin(kTheta);
  w.model.gravity[2] = -kG * std::cos(kTheta);
}

double mean_x(const Simulation& w) {
  double sum = 0;
  for (int64_t p = 0; p < w.cloth.grid.n(); ++p) sum += w.cloth.x()[3 * p];
  return sum / double(w.cloth.grid.n());
}

// The largest in-plane displacement of any particle from x0.
double largest_slip(const Simulation& w, const std::vector<double>& x0) {
  double most = 0;
  for (int64_t p = 0; p < w.cloth.grid.n(); ++p)
    most = std::max(most, std::hypot(w.cloth.x()[3 * p] - x0[3 * p], w.cloth.x()[3 * p + 1] - x0[3 * p + 1]));
  return most;
}

// mu = 0.6 > tan(20 deg): the cloth stays. Friction lags by a step and
// ramps up over a slip eps, so a held particle may creep by less than eps a
// step: 100 steps leave it within 100 eps (0.1 mm), where without friction
// it slides g sin(theta) t^2 / 2 = 17 mm.
TEST(Friction, HoldsTheClothWhenMuExceedsTheSlope) {
  const auto world = resting_cloth(0.6);
  Simulation& w = *world;
  ASSERT_GT(0.6, std::tan(kTheta));
  const std::vector<double> x0(w.cloth.x(), w.cloth.x() + 3 * w.cloth.grid.n());
  tilt(w);
  const int steps = 100;
  for (int k = 0; k < steps; ++k) ASSERT_TRUE(w.step().converged) << "step " << k;
  EXPECT_LT(largest_slip(w, x0), steps * w.model.contact.slip);
}

// A held cloth creeps a fraction of eps a step (the lagged ramp), which at
// 0.1 ms steps is faster than a strict rest_speed (5 mm/s against 2): the
// rest rule counts such a creep as calm, so the tilted held cloth comes to rest.
TEST(Friction, CreepWithinTheRampCountsAsRest) {
  const double dt = 1e-4;
  const auto world = resting_cloth(0.6);
  Simulation& w = *world;
  w.scene.solver.rest_speed = 2e-3;
  w.scene.solver.dt_max = dt;  // from here on the fixed step is dt
  w.loop->set_solver(w.scene.solver);
  w.cloth.dt = dt;
  tilt(w);
  double fastest = 0, shortest = dt;
  for (int k = 0; k < 300 && !w.summary().at_rest; ++k) {
    const StepStats st = w.step();
    ASSERT_TRUE(st.converged) << "step " << k;
    fastest = std::max(fastest, st.max_speed);
    shortest = std::min(shortest, st.dt);
    w.ending(st);
  }
  EXPECT_TRUE(w.summary().at_rest);
  EXPECT_GT(fastest, w.scene.solver.rest_speed);  // at rest by the creep's allowance
  EXPECT_LT(fastest, kCreepSlips * w.model.contact.slip / shortest);
}

// mu = 0.2 < tan(20 deg): the cloth slides at g (sin - mu cos) = 1.51 m/s^2
// (3.35 without friction). Measured from the mean x over steps 40-100, by
// the change of its velocity (exact for a constant acceleration).
TEST(Friction, SlidingClothAcceleratesAtGTimesSinMinusMuCos) {
  const double mu = 0.2;
  const auto world = resting_cloth(mu);
  Simulation& w = *world;
  tilt(w);
  std::vector<double> x, t;
  for (int k = 0; k <= 100; ++k) {
    ASSERT_TRUE(w.step().converged) << "step " << k;
    x.push_back(mean_x(w));
    t.push_back(w.cloth.time);
  }
  auto velocity = [&](int k) { return (x[k] - x[k - 1]) / (t[k] - t[k - 1]); };
  const int a = 40, b = 100;
  const double accel = (velocity(b) - velocity(a)) / (0.5 * (t[b] + t[b - 1]) - 0.5 * (t[a] + t[a - 1]));
  const double want = kG * (std::sin(kTheta) - mu * std::cos(kTheta));
  EXPECT_NEAR(accel, want, 0.02 * want);
}

// Friction switched on against a surface the cloth never touches (no box
// or sphere; the floor frictionless) runs the friction code at every
// particle, adding nothing: the states are bit for bit those of mu = 0.
TEST(Friction, NothingHeldLeavesTheStatesBitForBit) {
  const auto plain_world = resting_cloth(0.0);
  Simulation& plain = *plain_world;
  const auto held_by_nothing_world = resting_cloth(0.0);
  Simulation& held_by_nothing = *held_by_nothing_world;
  held_by_nothing.model.contact.friction = 0.5;  // obstacle shape none: nothing to hold
  ASSERT_TRUE(held_by_nothing.model.contact.has_friction());
  const double start = mean_x(plain);
  for (Simulation* w : {&plain, &held_by_nothing}) {
    tilt(*w);
    w->advance(30);
  }
  EXPECT_GT(mean_x(plain) - start, 1e-4);  // it slid
  EXPECT_TRUE(plain.cloth.z == held_by_nothing.cloth.z);
}

}  // namespace
}  // namespace drape::test
