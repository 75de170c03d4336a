// Cloth-cloth contact (solver/self_contact.hpp): a sheet folded over onto
// itself and dropped, whose upper flap must come to rest on the lower half
// instead of falling through it; the new term's gradient against central
// differences; K assembled against the product with pairs in contact; the
// same bits on 1 and 2 threads.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <random>

#include "solver/memory_table.hpp"
#include "solver/multigrid/block_matrix.hpp"
#include "support/assembled_check.hpp"
#include "solver/checksum.hpp"
#include "support/folded_strip.hpp"

namespace drape::test {
namespace {

// The closest two particles that are not mesh neighbours (rest distance
// above twice the pair distance, as the pair list excludes them) come.
// Only active particles count (an AMRC mesh's others lie on their leaves).
double closest_pair(const Simulation& w, double pair_distance) {
  const Grid& g = w.cloth.grid;
  double best = 1e300;
  for (int64_t p = 0; p < g.n(); ++p)
    for (int64_t q = p + 1; q < g.n(); ++q) {
      if (!w.cloth.active(p) || !w.cloth.active(q)) continue;
      const double di = (g.i_of(q) - g.i_of(p)) * g.hi, dj = (g.j_of(q) - g.j_of(p)) * g.hj;
      if (di * di + dj * dj <= 4 * pair_distance * pair_distance * (1 + 1e-9)) continue;
      double d2 = 0;
      for (int k = 0; k < 3; ++k) d2 += std::pow(w.cloth.z[3 * p + k] - w.cloth.z[3 * q + k], 2);
      best = std::min(best, std::sqrt(d2));
    }
  return best;
}

struct Dropped {
  double closest, pair_distance;
  double listed_closest;  // SelfContact::closest: the pair list's nearest pair (report.json's min_distance)
  std::vector<double> z;
  bool all_converged = true;
};

// The folded strip dropped (by default its flap 2.4 pair distances above
// the lower half) and run for 0.4 s, at rest.
Dropped drop(bool self_contact, int threads = 1, double end = 0.4, double gap_in_h = 2.4,
             Preconditioner pre = Preconditioner::Jacobi) {
  omp_set_num_threads(threads);
  Scene s = strip_scene(self_contact);
  s.solver.preconditioner = pre;
  Simulation w(s, test_fabric());
  fold(w, gap_in_h);
  Dropped out{};
  int steps = 0;
  while (w.cloth.time < end) out.all_converged &= w.step().converged, ++steps;
  if (getenv("DRAPE_DEBUG_SELF"))
    printf("self %d: %d steps, %llu builds, %lld listed, t %.3f\n", int(self_contact), steps,
           (unsigned long long)w.loop->evaluator().self_contact().builds(),
           (long long)w.loop->evaluator().self_contact().listed(), w.cloth.time);
  out.pair_distance = 2 * w.model.contact.thickness;
  out.closest = closest_pair(w, out.pair_distance);
  out.listed_closest = w.loop->evaluator().self_contact().closest(w.lists.particles, w.cloth.z.data());
  out.z = w.cloth.z;
  omp_set_num_threads(1);
  return out;
}

// The flap rests on the lower half: no two particles that are not mesh
// neighbours closer than the pair distance D less a quarter of it. A pair
// pressed D/4 in pushes with k (D/4)^2 / delta = 2500 particle weights
// (k holds 10^4 weights at delta = D/2, the ramp is delta/2): far more than
// the few weights a resting flap puts on a particle, so a resting state
// stays well inside that. Without self-contact the flap falls through the
// lower half onto the floor: the same check fails.
TEST(SelfContact, FoldedStripRestsOnItself) {
  const Dropped with = drop(true);
  EXPECT_TRUE(with.all_converged);
  EXPECT_GE(with.closest, 0.75 * with.pair_distance) << "closest " << with.closest << " of " << with.pair_distance;
  const Dropped without = drop(false);
  if (getenv("DRAPE_DEBUG_SELF")) printf("closest %g / %g, without %g\n", with.closest, with.pair_distance, without.closest);
  EXPECT_LT(without.closest, 0.75 * without.pair_distance)
      << "without self-contact the flap should pass through the lower half";
  EXPECT_EQ(without.listed_closest, HUGE_VAL) << "no pair list without self-contact";
}

// The flap starts just above the lower half (1.02 D), so that pairs come
// into contact within a few steps and stay; 50 ms of it.
// With the multigrid preconditioner: K assembled with the pairs' blocks,
// its pattern and levels rebuilt as the pair list is.
TEST(SelfContact, FoldedStripRestsOnItselfWithMultigrid) {
  const Dropped mg = drop(true, 1, 0.4, 2.4, Preconditioner::Multigrid);
  EXPECT_TRUE(mg.all_converged);
  EXPECT_GE(mg.closest, 0.75 * mg.pair_distance) << "closest " << mg.closest << " of " << mg.pair_distance;
}

TEST(SelfContact, SameBitsOnOneAndTwoThreads) {
  const Dropped one = drop(true, 1, 0.05, 1.02), two = drop(true, 2, 0.05, 1.02);
  EXPECT_LT(one.closest, one.pair_distance) << "pairs should be in contact";
  // Within the pair distance the list's nearest pair is the nearest of all.
  EXPECT_EQ(one.listed_closest, one.closest);
  EXPECT_EQ(two.listed_closest, one.closest);
  ASSERT_EQ(one.z.size(), two.z.size());
  EXPECT_EQ(std::memcmp(one.z.data(), two.z.data(), one.z.size() * sizeof(double)), 0);
}

// A folded strip pressed together (the flap half a pair distance above the
// lower half), jittered: pairs in contact on both sides of the ramp.
std::unique_ptr<Simulation> pressed_world(unsigned seed) {
  auto world = std::make_unique<Simulation>(strip_scene(true), test_fabric());
  Simulation& w = *world;
  fold(w, 0.5);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int64_t k = 0; k < 3 * w.cloth.grid.n(); ++k) w.cloth.z[k] += 0.1 * kH * u(rng);
  w.model.dt = w.model.dt_prev = 1e-3;
  w.loop->freeze_bend_axes();
  w.loop->evaluator().hysteresis_forces(w.cloth.z.data());
  return world;
}

int pairs_in_contact(const Simulation& w) {
  const SelfContact& sc = w.loop->evaluator().self_contact();
  int n = 0;
  const std::vector<int64_t>& items = w.lists.particles.items;
  for (size_t k = 0; k < items.size(); ++k)
    sc.for_partners(int64_t(k), [&](int64_t q) {
      PairTerm t;
      n += sc.term(w.cloth.z.data(), items[k], q, t);
    });
  return n;
}

// The positions turned by `angle` about an oblique axis and shifted off
// the hash's cell planes: the sheet then crosses cells along every axis
// (flat, it would lie in one layer of cells and never need the others).
void turn_and_shift(Simulation& w, double angle) {
  const double a[3] = {1 / std::sqrt(14.0), 2 / std::sqrt(14.0), 3 / std::sqrt(14.0)};
  const double c = std::cos(angle), s = std::sin(angle), shift[3] = {0.0137, -0.0071, 0.0093};
  for (int64_t p = 0; p < w.cloth.grid.n(); ++p) {
    double* x = &w.cloth.z[3 * p];
    const double ax = a[0] * x[0] + a[1] * x[1] + a[2] * x[2];
    const double cr[3] = {a[1] * x[2] - a[2] * x[1], a[2] * x[0] - a[0] * x[2], a[0] * x[1] - a[1] * x[0]};
    double r[3];
    for (int i = 0; i < 3; ++i) r[i] = x[i] * c + cr[i] * s + a[i] * ax * (1 - c);  // Rodrigues
    for (int i = 0; i < 3; ++i) x[i] = r[i] + shift[i];
  }
}

// The pair list is exactly the pairs a search of every two listed particles
// finds at the build's positions: within the search reach (2D) and not mesh
// neighbours, each particle's ascending by id. The pressed strip's pairs lie
// at all distances and directions up to and past the reach, and turned it
// crosses the hash's cells along every axis, so a spatial hash that skips a
// cell it must search, or lists a pair twice, is seen.
TEST(SelfContact, ListIsEveryPairWithinReach) {
  for (unsigned seed : {3u, 4u}) {
    const auto world = pressed_world(seed);
    Simulation& w = *world;
    turn_and_shift(w, 0.3 * seed);
    Evaluator& ev = w.loop->evaluator();
    ev.evaluate(w.cloth.z.data(), nullptr);  // the first build: at these positions
    const SelfContact& sc = ev.self_contact();
    ASSERT_EQ(sc.builds(), 1u);
    const Grid& g = w.cloth.grid;
    const double reach = 2 * sc.distance(), exclude2 = reach * reach * (1 + 1e-9);
    const double* x = w.cloth.z.data();
    const std::vector<int64_t>& items = w.lists.particles.items;
    int64_t listed = 0, near_reach = 0;
    for (size_t k = 0; k < items.size(); ++k) {
      const int64_t p = items[k];
      std::vector<int64_t> want, got;
      for (int64_t q : items) {
        if (q == p) continue;
        const double di = (g.i_of(q) - g.i_of(p)) * g.hi, dj = (g.j_of(q) - g.j_of(p)) * g.hj;
        if (di * di + dj * dj <= exclude2) continue;
        double d2 = 0;
        for (int i = 0; i < 3; ++i) d2 += (x[3 * q + i] - x[3 * p + i]) * (x[3 * q + i] - x[3 * p + i]);
        if (d2 < reach * reach) want.push_back(q);
        near_reach += d2 > 0.8 * reach * reach && d2 < 1.2 * reach * reach;
      }
      std::sort(want.begin(), want.end());  // the list's order: ascending id
      sc.for_partners(int64_t(k), [&](int64_t q) { got.push_back(q); });
      ASSERT_EQ(got, want) << "particle " << p;
      listed += int64_t(got.size());
    }
    EXPECT_EQ(listed, sc.listed());
    ASSERT_GT(listed, 200) << "too few pairs to tell a search from another";
    ASSERT_GT(near_reach, 100) << "too few pairs about the reach to see a cell skipped";
  }
}

// The list does not depend on the thread count, whether each thread's
// partners fit its share of the list's room (one search a particle) or
// outgrow it (searched again into room made for them). The first build
// outgrows the room it was given (the pressed strip has more pairs a
// particle than reserved); the second, after a particle moved, fits.
TEST(SelfContact, ListIsTheSameOnAnyThreadCount) {
  std::vector<std::vector<int64_t>> first;
  bool once = false, twice = false;
  for (int threads : {1, 2, 3, 8, 16}) {
    omp_set_num_threads(threads);
    const auto world = pressed_world(3);
    Simulation& w = *world;
    Evaluator& ev = w.loop->evaluator();
    ev.evaluate(w.cloth.z.data(), nullptr);
    const SelfContact& sc = ev.self_contact();
    const uint64_t before = sc.searched_twice();
    twice = twice || before > 0;
    w.cloth.z[3 * w.lists.particles.items[0] + 2] += 2 * sc.distance();  // beyond the slack: built again
    ev.evaluate(w.cloth.z.data(), nullptr);
    ASSERT_EQ(sc.builds(), 2u);
    once = once || sc.searched_twice() == before;
    std::vector<std::vector<int64_t>> lists(w.lists.particles.items.size());
    for (size_t k = 0; k < lists.size(); ++k) sc.for_partners(int64_t(k), [&](int64_t q) { lists[k].push_back(q); });
    if (first.empty()) first = lists;
    ASSERT_EQ(lists, first) << threads << " threads";
  }
  omp_set_num_threads(1);
  EXPECT_TRUE(once) << "no build fitted its shares: the single search went untested";
  EXPECT_TRUE(twice) << "no build outgrew its room: the second search went untested";
}

// The Newton term's gradient (self-contact's -J^T r included, J with the
// normal's curvature) against central differences of the cost, position by
// position, relative to the largest entry.
TEST(SelfContact, GradientMatchesCentralDifferences) {
  for (unsigned seed : {1u, 2u}) {
    const auto world = pressed_world(seed);
    Simulation& w = *world;
    Evaluator& ev = w.loop->evaluator();
    w.model.use_stretch = w.model.use_bend = w.model.use_shear = false;
    w.model.memory = 0;  // the memory term counts with its element's
    std::vector<double> ga(w.cloth.z.size());
    ev.evaluate(w.cloth.z.data(), ga.data());
    ASSERT_GT(pairs_in_contact(w), 20);
    std::vector<double> z = w.cloth.z;
    double scale = 0, worst = 0;
    for (int64_t p : w.lists.particles.items)
      for (int k = 0; k < 3; ++k) {
        const int64_t u = 3 * p + k;
        const double h = 1e-6 * kH, z0 = z[u];
        z[u] = z0 + h;
        const double cp = ev.evaluate(z.data(), nullptr).newton;
        z[u] = z0 - h;
        const double cm = ev.evaluate(z.data(), nullptr).newton;
        z[u] = z0;
        const double fd = (cp - cm) / (2 * h);
        scale = std::max({scale, std::fabs(fd), std::fabs(ga[u])});
        worst = std::max(worst, std::fabs(fd - ga[u]));
      }
    EXPECT_LE(worst, 1e-6 * scale) << "seed " << seed;
  }
}

// K assembled (multigrid's finest level) is the product's operator with
// self-contact's blocks, and symmetric: partner columns included.
TEST(SelfContact, AssembledStiffnessMatchesTheProduct) {
  const auto world = pressed_world(3);
  Simulation& w = *world;
  Evaluator& ev = w.loop->evaluator();
  ev.settled_cost(w.cloth.z.data());
  ASSERT_GT(pairs_in_contact(w), 20);
  std::vector<double> diag;
  expect_assembled_is_the_product(w, "self-contact", diag);
  const size_t n = w.cloth.z.size();
  const std::vector<int64_t>& ids = w.lists.particles.items;
  // The diagonal's self-contact share: the trace of each particle's block / 3.
  const auto plain_world = pressed_world(3);
  Simulation& plain = *plain_world;
  plain.model.self_contact = false;
  std::vector<double> dplain(n, 0.0);
  plain.loop->evaluator().settled_cost(plain.cloth.z.data());
  plain.loop->evaluator().stiffness_diagonal(plain.cloth.z.data(), dplain.data());
  const SelfContact& sc = ev.self_contact();
  for (size_t k = 0; k < ids.size(); ++k) {
    const int64_t p = ids[k];
    EXPECT_NEAR(diag[3 * p] - dplain[3 * p], sc.slope_sum(int64_t(k), p, w.cloth.z.data()) / 3, 1e-12 * diag[3 * p]);
  }
}

// The pair list does not depend on when it was built: one built at the
// step's start and kept while particles move less than D/2, and one built
// afresh at the current positions, give the same forces bit for bit.
TEST(SelfContact, ForcesDoNotDependOnWhenTheListWasBuilt) {
  const auto world = pressed_world(4);
  Simulation& w = *world;
  const auto fresh_world = pressed_world(4);
  Simulation& fresh = *fresh_world;
  Evaluator& ev = w.loop->evaluator();
  ev.evaluate(w.cloth.z.data(), nullptr);
  const uint64_t built = ev.self_contact().builds();
  std::uniform_real_distribution<double> u(-1, 1);
  const double move = 0.2 * ev.self_contact().distance();  // < D/2 over the step: the list holds
  for (double* z : {w.cloth.z.data(), fresh.cloth.z.data()}) {
    std::mt19937_64 same(9);
    for (int64_t k = 0; k < 3 * w.cloth.grid.n(); ++k) z[k] += move * u(same) / std::sqrt(3.0);
  }
  ev.evaluate(w.cloth.z.data(), nullptr);
  EXPECT_EQ(ev.self_contact().builds(), built) << "the list should have held";
  fresh.loop->evaluator().evaluate(fresh.cloth.z.data(), nullptr);
  ASSERT_GT(pairs_in_contact(w), 20);
  EXPECT_TRUE(ev.residual() == fresh.loop->evaluator().residual());
}

// A new pair list on the same own numbering (one rank: no contact ghosts,
// no list change) gives the product of a world that built that list first:
// the partners' kept indices follow the list.
TEST(SelfContact, ProductFollowsANewPairList) {
  const auto world = pressed_world(6), fresh_world = pressed_world(6);
  Simulation& w = *world;
  Simulation& fresh = *fresh_world;
  const size_t n = w.cloth.z.size();
  std::vector<double> v(n), kv(n, 0.0), diag(n), fresh_kv(n, 0.0);
  auto newton_order = [&](Simulation& s, double* z, std::vector<double>& out) {
    Evaluator& ev = s.loop->evaluator();
    ev.evaluate(z, nullptr);
    ev.settled_cost(z);
    ev.stiffness_diagonal(z, diag.data());
    for (size_t k = 0; k < n; ++k) v[k] = 1e-3 * double(int(k * 7919 % 13) - 6);
    ev.stiffness_product(z, v.data(), out.data());
  };
  std::vector<double> apart = w.cloth.z;  // the flap lifted 3 pair distances: other pairs listed
  for (int64_t p = 0; p < w.cloth.grid.n(); ++p)
    if (w.cloth.z[3 * p + 2] > 0.75 * kH) apart[3 * p + 2] += 3 * kH;
  newton_order(w, apart.data(), kv);
  const uint64_t built = w.loop->evaluator().self_contact().builds();
  const int64_t listed = w.loop->evaluator().self_contact().listed();
  newton_order(w, w.cloth.z.data(), kv);
  ASSERT_GT(w.loop->evaluator().self_contact().builds(), built) << "the list should have been built again";
  ASSERT_NE(w.loop->evaluator().self_contact().listed(), listed) << "the same pairs: the test would not see stale indices";
  newton_order(fresh, fresh.cloth.z.data(), fresh_kv);
  ASSERT_GT(pairs_in_contact(w), 20);
  for (int64_t p : w.lists.particles.items)
    for (int k = 0; k < 3; ++k) ASSERT_EQ(kv[3 * p + k], fresh_kv[3 * p + k]) << "particle " << p;
}

// The pair list holds one 32-bit number a listed partner (its hashed
// index stands for both its id and its own-numbering index), and is in the
// evaluator's memory table; a rank's own partners need no index beside it
// (only contact ghosts have one: none on one rank).
TEST(SelfContact, PartnersAreOneNumberEachInTheMemoryTable) {
  const auto world = pressed_world(5);
  Simulation& w = *world;
  Evaluator& ev = w.loop->evaluator();
  ev.settled_cost(w.cloth.z.data());
  ASSERT_GT(pairs_in_contact(w), 20);
  MemoryTable t;
  ev.memory(t);
  size_t partners = 0, ghost_indices = 0, rows = 0;
  for (const MemoryTable::Row& r : t.rows) {
    if (r.owner != "SelfContact") continue;
    if (r.array == "partners (hashed indices)") partners += r.bytes, ++rows;
    if (r.array == "contact ghosts' own-numbering indices") ghost_indices += r.bytes, ++rows;
  }
  ASSERT_EQ(rows, 2u) << "a row renamed: the sums below would be vacuous";
  EXPECT_GE(partners, sizeof(int32_t) * size_t(ev.self_contact().listed()));
  EXPECT_EQ(ghost_indices, 0u);
}

// The flap's lowest particle (past the fold) over the lower half's highest
// (before it): about D when the flap rests on the lower half, about 0 when
// it fell through onto the floor.
double flap_clearance(const Simulation& w) {
  const Grid& g = w.cloth.grid;
  double flap = 1e300, lower = -1e300;
  for (int i = 0; i < g.ni; ++i) {
    for (int j = 0; j <= 8; ++j) lower = std::max(lower, w.cloth.z[3 * g.id(i, j) + 2]);
    for (int j = 16; j < g.nj; ++j) flap = std::min(flap, w.cloth.z[3 * g.id(i, j) + 2]);
  }
  return flap - lower;
}

struct AmrcDrop {
  Dropped d;
  double clearance = 0;
  int64_t refined_near = 0;
  std::string checksum;
};

// The folded strip with AMRC on (leaves up to 4 spacings wide), dropped from
// 2.4 pair distances by the drape program's simulation on one rank.
AmrcDrop drop_with_amrc(bool self_contact, int threads, double end = 0.4) {
  omp_set_num_threads(threads);
  RunOptions opt;
  opt.output_dir = std::string(DRAPE_TEST_TMP) + "/self_contact_amrc_" + std::to_string(threads) +
                   (self_contact ? "_on" : "_off");
  opt.quiet = true;
  Simulation w(strip_scene(self_contact, true), test_fabric(), opt, MPI_COMM_SELF);
  fold(w, 2.4);
  w.start();
  AmrcDrop out;
  out.d.all_converged = run_until(w, end);
  out.d.pair_distance = 2 * w.model.contact.thickness;
  out.d.closest = closest_pair(w, out.d.pair_distance);
  out.clearance = flap_clearance(w);
  out.refined_near = w.summary().refined_near;
  out.checksum = state_checksum(w.cloth, w.tiling, w.owned(), w.red()).hex();
  if (getenv("DRAPE_DEBUG_SELF"))
    printf("amrc self %d: closest %g of %g, clearance %g, refined %lld near %lld, active %lld, listed %lld\n",
           int(self_contact), out.d.closest, out.d.pair_distance, out.clearance, (long long)w.summary().refined,
           (long long)out.refined_near, (long long)active_particles(w.cloth),
           (long long)w.loop->evaluator().self_contact().listed());
  omp_set_num_threads(1);
  return out;
}

// AMRC on: the leaves near the other sheet stay at the finest level
// (amrc/near.cpp), so self-contact holds the flap on the lower half as on
// the uniform mesh. Without that rule the flat halves coarsen and the flap
// passes between the lower half's particles (tried: clearance about 0,
// though the closest pair stays near 0.8 D); without self-contact it falls
// through. The same bits on 1 and 2 threads.
TEST(SelfContact, FoldedStripRestsOnItselfWithAmrc) {
  const AmrcDrop with = drop_with_amrc(true, 1);
  EXPECT_TRUE(with.d.all_converged);
  EXPECT_GE(with.d.closest, 0.75 * with.d.pair_distance) << "closest " << with.d.closest << " of " << with.d.pair_distance;
  EXPECT_GE(with.clearance, 0.75 * with.d.pair_distance) << "the flap passed through the lower half";
  const AmrcDrop without = drop_with_amrc(false, 1);
  EXPECT_LT(without.clearance, 0.5 * without.d.pair_distance) << "without self-contact the flap should fall through";
  EXPECT_EQ(drop_with_amrc(true, 2).checksum, with.checksum);
}

}  // namespace
}  // namespace drape::test
