// Three ranks: self-contact across ranks. The folded strip dropped onto
// itself, run by the drape program's simulation on 1 rank with 2 threads,
// on 2 and on 3 ranks (sub-communicators of the three), ends in the
// same state checksum; its pairs reach across ranks (contact ghosts), and
// the state differs from the same run without self-contact; with the
// multigrid preconditioner too. The cost's gradient and K assembled (the
// multigrid's finest level, entry by entry) at a pressed fold are the same
// on 1, 2 and 3 ranks (K on an AMRC mesh too, its hanging particles between
// two ranks' particles), and so is a V-cycle with the finest level divided
// over the ranks and whole.
#include <gtest/gtest.h>
#include <mpi.h>
#include <omp.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>

#include "decomp/collective.hpp"
#include "solver/checksum.hpp"
#include "solver/multigrid/block_matrix.hpp"
#include "solver/multigrid/divided_level.hpp"
#include "solver/multigrid/multigrid.hpp"
#include "solver/multigrid/rank_rows.hpp"
#include "support/folded_strip.hpp"

namespace drape::test {
namespace {

int rank() { return rank_of(MPI_COMM_WORLD); }

// body(comm) on the first `ranks` world ranks, comm a sub-communicator of them;
// the other ranks skip it.
template <class Body>
void on_first_ranks(int ranks, Body&& body) {
  MPI_Comm comm;
  MPI_Comm_split(MPI_COMM_WORLD, rank() < ranks ? 0 : MPI_UNDEFINED, rank(), &comm);
  if (comm == MPI_COMM_NULL) return;
  body(comm);
  MPI_Comm_free(&comm);
}

// A quiet run writing into the test's scratch directory `name`.
RunOptions quiet_run(const std::string& name) {
  RunOptions opt;
  opt.output_dir = std::string(DRAPE_TEST_TMP) + "/" + name;
  opt.quiet = true;
  return opt;
}

// A broadcast from rank 0 whose waiting ranks sleep between polls: a rank
// left out of a run must not take the cores its threads spin on.
void quiet_bcast(void* data, int count, MPI_Datatype type) {
  MPI_Request req;
  MPI_Ibcast(data, count, type, 0, MPI_COMM_WORLD, &req);
  int done = 0;
  for (MPI_Test(&req, &done, MPI_STATUS_IGNORE); !done; MPI_Test(&req, &done, MPI_STATUS_IGNORE)) usleep(2000);
}

struct Outcome {
  std::string checksum;
  int64_t contact_ghosts = 0;  // over the ranks, at the last build
  int64_t in_contact = 0;      // pairs closer than the pair distance at the end, over the ranks
  uint64_t builds = 0;
  int64_t refined_near = 0;  // AMRC's splits for the other sheet nearby
  int64_t multigrid_builds = 0;
};

// Pairs of p's listed partners in contact at the end, over this rank's particles.
int64_t pairs_in_contact(const Simulation& w) {
  const SelfContact& sc = w.loop->evaluator().self_contact();
  int64_t n = 0;
  const std::vector<int64_t>& items = w.lists.particles.items;
  for (size_t k = 0; k < items.size(); ++k)
    sc.for_partners(int64_t(k), [&](int64_t q) {
      PairTerm t;
      n += sc.term(w.cloth.z.data(), items[k], q, t);
    });
  return n;
}

// The flap dropped from just above the lower half (1.02 pair distances), so
// that pairs come into contact within a few steps, for `end` seconds, on the
// first `ranks` ranks with `threads` threads; every rank gets rank 0's result.
// With amrc, the wide sheet folded at 16 spacings and dropped from 1.5 pair
// distances, AMRC adapting as the program does.
Outcome drop(int ranks, int threads, bool self_contact, SolverMethod method = SolverMethod::Newton,
             double end = 0.06, bool amrc = false, Preconditioner pc = Preconditioner::Jacobi) {
  Outcome out;
  char sum[40] = {0};
  int64_t counts[5] = {0, 0, 0, 0, 0};
  on_first_ranks(ranks, [&](MPI_Comm comm) {
    omp_set_num_threads(threads);
    const RunOptions opt = quiet_run("mpi_self_contact_" + std::to_string(ranks) + (self_contact ? "_on" : "_off") +
                                     (method == SolverMethod::Cg ? "_cg" : "") + (amrc ? "_amrc" : "") +
                                     (pc == Preconditioner::Multigrid ? "_mg" : ""));
    Scene scene = amrc ? wide_strip_scene(self_contact) : strip_scene(self_contact);
    scene.solver.method = method;
    scene.solver.preconditioner = pc;
    Simulation w(scene, test_fabric(), opt, comm);
    if (amrc)
      fold(w, 1.5, 16);
    else
      fold(w, 1.02);
    w.start();
    run_until(w, end);
    const std::string hex = state_checksum(w.cloth, w.tiling, w.owned(), w.red()).hex();
    hex.copy(sum, sizeof sum - 1);
    const SelfContact& sc = w.loop->evaluator().self_contact();
    counts[0] = w.red().sum_i64(sc.contact_ghosts());
    counts[1] = w.red().sum_i64(pairs_in_contact(w));
    counts[2] = int64_t(sc.builds());
    counts[3] = w.summary().refined_near;
    counts[4] = w.loop->newton().multigrid_builds();
    omp_set_num_threads(1);
  });
  quiet_bcast(sum, sizeof sum, MPI_CHAR);
  quiet_bcast(counts, 5, MPI_INT64_T);
  out.checksum = sum;
  out.contact_ghosts = counts[0];
  out.in_contact = counts[1];
  out.builds = uint64_t(counts[2]);
  out.refined_near = counts[3];
  out.multigrid_builds = counts[4];
  return out;
}

// The drape runs Newton with pairs in contact across rank borders: its
// products K v read those partners' v, numbered as the rank's others and
// refreshed by Halo::exchange_at, so this compares that path too.
TEST(MpiSelfContact, SameStateOnOneTwoAndThreeRanks) {
  const Outcome one = drop(1, 2, true), two = drop(2, 1, true), three = drop(3, 1, true);
  ASSERT_FALSE(one.checksum.empty());
  if (getenv("DRAPE_DEBUG_SELF") && rank() == 0) printf("folded strip: %s\n", one.checksum.c_str());
  EXPECT_GT(one.in_contact, 20) << "pairs should be in contact";
  EXPECT_EQ(one.contact_ghosts, 0);
  EXPECT_GT(two.contact_ghosts, 0) << "no partner on another rank: the test does not cover contact ghosts";
  EXPECT_GT(three.contact_ghosts, 0);
  EXPECT_EQ(two.checksum, one.checksum);
  EXPECT_EQ(three.checksum, one.checksum);
  EXPECT_EQ(two.in_contact, one.in_contact);
  EXPECT_EQ(three.in_contact, one.in_contact);
  EXPECT_EQ(two.builds, one.builds);
  EXPECT_EQ(three.builds, one.builds);
  // The pairs change the state: the comparison above could fail.
  const Outcome off = drop(2, 1, false);
  EXPECT_NE(off.checksum, one.checksum);
}

// The same drop with the multigrid: its finest level is K gathered from
// every rank's rows, contact ghosts' columns included.
TEST(MpiSelfContact, MultigridSameStateOnOneTwoAndThreeRanks) {
  const SolverMethod nt = SolverMethod::Newton;
  const Preconditioner mg = Preconditioner::Multigrid;
  const Outcome one = drop(1, 2, true, nt, 0.06, false, mg), two = drop(2, 1, true, nt, 0.06, false, mg),
                three = drop(3, 1, true, nt, 0.06, false, mg);
  ASSERT_FALSE(one.checksum.empty());
  EXPECT_GT(one.in_contact, 20) << "pairs should be in contact";
  EXPECT_GT(one.multigrid_builds, 0) << "no multigrid built";
  EXPECT_GT(two.contact_ghosts, 0) << "no partner on another rank: the test does not cover contact ghosts";
  EXPECT_GT(three.contact_ghosts, 0);
  EXPECT_EQ(two.checksum, one.checksum);
  EXPECT_EQ(three.checksum, one.checksum);
  EXPECT_EQ(two.multigrid_builds, one.multigrid_builds);
  EXPECT_EQ(three.multigrid_builds, one.multigrid_builds);
}

// AMRC on: the sheet starts on leaves 4 spacings wide, the near mask splits
// those where the flap faces the lower half (positions gathered over ranks),
// the pair list follows each new mesh; 1 rank with 2 threads, 2 and 3 ranks
// end in the same state.
TEST(MpiSelfContact, SameStateOnOneTwoAndThreeRanksWithAmrc) {
  const double end = 0.025;  // the flap lands at 0.02 s (and the tight fold springs it open after 0.03 s)
  const Outcome one = drop(1, 2, true, SolverMethod::Newton, end, true);
  const Outcome two = drop(2, 1, true, SolverMethod::Newton, end, true);
  const Outcome three = drop(3, 1, true, SolverMethod::Newton, end, true);
  ASSERT_FALSE(one.checksum.empty());
  if (getenv("DRAPE_DEBUG_SELF") && rank() == 0)
    printf("wide strip with AMRC: %s, %lld near splits, %lld in contact, %lld/%lld contact ghosts\n",
           one.checksum.c_str(), (long long)one.refined_near, (long long)one.in_contact,
           (long long)two.contact_ghosts, (long long)three.contact_ghosts);
  EXPECT_GT(one.refined_near, 0) << "no leaf split for the other sheet";
  EXPECT_GT(one.in_contact, 20) << "pairs should be in contact";
  EXPECT_GT(three.contact_ghosts, 0) << "no partner on another rank: the test does not cover contact ghosts";
  EXPECT_EQ(two.checksum, one.checksum);
  EXPECT_EQ(three.checksum, one.checksum);
  EXPECT_EQ(two.refined_near, one.refined_near);
  EXPECT_EQ(three.refined_near, one.refined_near);
  EXPECT_EQ(three.builds, one.builds);
  const Outcome off = drop(2, 1, false, SolverMethod::Newton, end, true);
  EXPECT_NE(off.checksum, one.checksum);
}

// The step's anchors set at the cloth's present state (dt 1 ms).
Evaluator& anchored(Simulation& w) {
  w.model.dt = w.model.dt_prev = 1e-3;
  w.loop->freeze_bend_axes();
  Evaluator& ev = w.loop->evaluator();
  ev.hysteresis_forces(w.cloth.z.data());
  return ev;
}

// The fold pressed to half a pair distance, its unknowns jittered alike on
// every rank count (same seed, whole grid), the step's anchors set.
Evaluator& press(Simulation& w) {
  fold(w, 0.5);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int64_t k = 0; k < 3 * w.cloth.grid.n(); ++k) w.cloth.z[k] += 0.1 * kH * u(rng);
  return anchored(w);
}

// The cost's gradient at a folded strip pressed together and jittered (as
// test_self_contact's), hashed over the free particles with their ids: its
// self-contact part reads the partners' residuals, which contact ghosts get
// with the residuals' exchange. Every rank gets rank 0's digest.
std::string pressed_gradient(int ranks) {
  char sum[40] = {0};
  on_first_ranks(ranks, [&](MPI_Comm comm) {
    Simulation w(strip_scene(true), test_fabric(), quiet_run("mpi_self_contact_grad_" + std::to_string(ranks)), comm);
    Evaluator& ev = press(w);
    std::vector<double> grad(w.cloth.z.size());
    ev.evaluate(w.cloth.z.data(), grad.data());
    uint64_t h = 0;
    for (int64_t p : w.lists.particles.items) {
      Hasher one{uint64_t(p)};
      for (int k = 0; k < 3; ++k) one.add(grad[3 * p + k]);
      h += one.value();
    }
    const std::string hex = std::to_string(w.red().sum_u64(h)) + "/" + std::to_string(w.red().sum_i64(pairs_in_contact(w)));
    hex.copy(sum, sizeof sum - 1);
  });
  quiet_bcast(sum, sizeof sum, MPI_CHAR);
  return sum;
}

TEST(MpiSelfContact, GradientSameOnOneTwoAndThreeRanks) {
  const std::string one = pressed_gradient(1);
  ASSERT_FALSE(one.empty());
  EXPECT_GT(std::stoll(one.substr(one.find('/') + 1)), 20) << "pairs should be in contact";
  EXPECT_EQ(pressed_gradient(2), one);
  EXPECT_EQ(pressed_gradient(3), one);
}

// K assembled at the pressed fold as the multigrid's finest level gets it:
// on one rank as the one-rank multigrid assembles it; on several, every
// rank's rows with global columns gathered in one rank's order (RankRows).
// Held on world rank 0 (the sub-communicators' rank 0); the counts on every
// rank.
struct Gathered {
  std::vector<int64_t> ids;  // row r's particle
  BlockMatrix K;
  int64_t ghost_blocks = 0;  // nonzero blocks in a contact ghost's column, over the ranks
  int64_t in_contact = 0;
};

// Nonzero blocks of `mine` (global columns of rr) whose particle is a
// contact ghost partner of this rank.
int64_t contact_ghost_blocks(const BlockMatrix& mine, const RankRows& rr, const SelfContact& sc) {
  const std::vector<int64_t>& g = sc.ghost_partners();
  int64_t n = 0;
  for (int64_t b = 0; b < mine.blocks(); ++b) {
    if (!std::binary_search(g.begin(), g.end(), rr.ids()[size_t(mine.col[b])])) continue;
    bool nonzero = false;
    for (int k = 0; k < 9; ++k) nonzero |= mine.val[9 * b + k] != 0.0;
    n += nonzero;
  }
  return n;
}

// K at ev's state into out (Newton's order: the settled cost, then the
// diagonal); on several ranks numbered by rr, and this rank's rows returned.
BlockMatrix gather_stiffness(Simulation& w, Evaluator& ev, int ranks, RankRows& rr, Gathered& out) {
  ev.evaluate(w.cloth.z.data(), nullptr);
  std::vector<double> diag(w.cloth.z.size());
  ev.stiffness_diagonal(w.cloth.z.data(), diag.data());
  BlockMatrix mine;
  if (ranks == 1) {
    ev.assemble_stiffness(out.K);
    out.ids = w.lists.particles.items;
    return mine;
  }
  rr.number(w.red(), w.tiling, w.lists.particles.items, w.cloth.grid.n());
  ev.assemble_stiffness(mine, &rr.column_of(), rr.size(), 1);
  rr.gather_matrix(w.red(), mine, out.K);
  out.ids = rr.ids();
  return mine;
}

Gathered pressed_stiffness(int ranks) {
  Gathered out;
  int64_t counts[2] = {0, 0};
  on_first_ranks(ranks, [&](MPI_Comm comm) {
    Simulation w(strip_scene(true), test_fabric(), quiet_run("mpi_self_contact_K_" + std::to_string(ranks)), comm);
    Evaluator& ev = press(w);
    RankRows rr;
    const BlockMatrix mine = gather_stiffness(w, ev, ranks, rr, out);
    if (ranks > 1) counts[0] = w.red().sum_i64(contact_ghost_blocks(mine, rr, ev.self_contact()));
    counts[1] = w.red().sum_i64(pairs_in_contact(w));
  });
  quiet_bcast(counts, 2, MPI_INT64_T);
  out.ghost_blocks = counts[0];
  out.in_contact = counts[1];
  return out;
}

// a and b entry by entry, bit for bit (world rank 0 holds them).
void expect_same_matrix(const Gathered& a, const Gathered& b, const std::string& label) {
  if (rank() != 0) return;
  ASSERT_EQ(a.ids, b.ids) << label;
  ASSERT_EQ(a.K.rows, b.K.rows) << label;
  ASSERT_EQ(a.K.start, b.K.start) << label;
  ASSERT_EQ(a.K.col, b.K.col) << label;
  ASSERT_EQ(a.K.val.size(), b.K.val.size()) << label;
  int64_t differ = 0;
  for (int64_t r = 0; r < a.K.rows; ++r)
    for (int64_t blk = a.K.start[r]; blk < a.K.start[r + 1]; ++blk)
      for (int k = 0; k < 9; ++k) {
        const double x = a.K.val[9 * blk + k], y = b.K.val[9 * blk + k];
        if (std::memcmp(&x, &y, sizeof x) == 0) continue;
        if (differ++ < 5)
          ADD_FAILURE() << label << ": K(" << a.ids[r] << ", " << a.ids[a.K.col[blk]] << ")[" << k << "] " << x
                        << " vs " << y;
      }
  EXPECT_EQ(differ, 0) << label << ": entries that differ";
}

TEST(MpiSelfContact, AssembledStiffnessSameOnOneTwoAndThreeRanks) {
  const Gathered one = pressed_stiffness(1), two = pressed_stiffness(2), three = pressed_stiffness(3);
  EXPECT_GT(one.in_contact, 20) << "pairs should be in contact";
  EXPECT_GT(two.ghost_blocks, 0) << "no contact block in another rank's column: the test does not cover them";
  EXPECT_GT(three.ghost_blocks, 0);
  if (rank() == 0) {
    EXPECT_GT(one.K.rows, 0);
  }
  expect_same_matrix(one, two, "2 ranks");
  expect_same_matrix(one, three, "3 ranks");
}

// K at a fold on an AMRC mesh: the wide strip starts on leaves 4
// spacings wide, folded half a pair distance apart, and one adaptation splits
// the leaves near the other sheet, so hanging particles lie on the coarse
// sides around them. A hanging particle's terms fold into its ends' rows and
// columns; an end may be another rank's particle. Counts over the ranks:
// hanging particles leaning on this rank's particles with an end that is
// another rank's.
struct HangingGathered : Gathered {
  int64_t hanging = 0, across = 0;
};

HangingGathered hanging_stiffness(int ranks) {
  HangingGathered out;
  int64_t counts[2] = {0, 0};
  on_first_ranks(ranks, [&](MPI_Comm comm) {
    Scene scene = wide_strip_scene(true);
    scene.amrc.refine = 1e30;  // splits for the other sheet only
    Simulation w(scene, test_fabric(), quiet_run("mpi_hanging_K_" + std::to_string(ranks)), comm);
    fold(w, 0.5, 20);
    w.start();
    w.adapt();
    RankRows rr;
    gather_stiffness(w, anchored(w), ranks, rr, out);
    if (ranks > 1) {
      const std::vector<int32_t>& col = rr.column_of();
      std::vector<char> mine_p(size_t(w.cloth.grid.n()), 0);
      for (int64_t p : w.lists.particles.items) mine_p[size_t(p)] = 1;
      int64_t across = 0;  // one end this rank's, the other another rank's free particle
      for (const HangingLink& l : w.lists.hanging)
        across += (mine_p[l.a] && col[l.b] >= 0 && !mine_p[l.b]) || (mine_p[l.b] && col[l.a] >= 0 && !mine_p[l.a]);
      counts[0] = w.red().sum_i64(across);
    }
    counts[1] = int64_t(w.lists.hanging.size());
  });
  quiet_bcast(counts, 2, MPI_INT64_T);
  out.across = counts[0];
  out.hanging = counts[1];
  return out;
}

TEST(MpiSelfContact, AssembledStiffnessWithHangingParticlesSameOnOneTwoAndThreeRanks) {
  const HangingGathered one = hanging_stiffness(1), two = hanging_stiffness(2), three = hanging_stiffness(3);
  if (getenv("DRAPE_DEBUG_SELF") && rank() == 0)
    printf("hanging particles %lld; between two ranks' particles: %lld on 2 ranks, %lld on 3\n",
           (long long)one.hanging, (long long)two.across, (long long)three.across);
  EXPECT_GT(one.hanging, 0) << "no hanging particle: the test does not cover them";
  EXPECT_GT(two.across, 0) << "no hanging particle between two ranks' particles";
  EXPECT_GT(three.across, 0) << "no hanging particle between two ranks' particles";
  expect_same_matrix(one, two, "2 ranks");
  expect_same_matrix(one, three, "3 ranks");
}

// One V-cycle at the pressed fold on `ranks` ranks, from a pseudo-random
// right-hand side (the same on every rank count), twice: whole (Multigrid::apply
// on K gathered, each rank taking its rows) and with the finest level
// divided (DividedLevel: each rank's rows of K, the ghosts' entries
// exchanged, level 1's right-hand side gathered). Counts over the ranks:
// entries that differ in any bit, the ghosts, and the ghosts' blocks in K
// that are self-contact's (partners on another rank). With the bilinear
// finest P, a third time with the levels built from no K whole (each rank's
// rows and its ring's): the entries of level 1's operator that differ from
// the whole build's in any bit, the cycle's entries that differ, and on the
// largest rank the bytes that build gathered (level 1's rows, the power
// iteration's vectors, here less the latter) against K's whole (RankRows::matrix_bytes).
struct Divided {
  int64_t differ = -1, ghosts = 0, contact_blocks = 0, levels = 0;
  int64_t level_one_differ = -1, built_differ = -1, build_bytes = 0, level_one_bytes = 0, whole_bytes = 0;
};

// Entries (pattern or values) in which two matrices differ in any bit.
int64_t matrix_differ(const BlockMatrix& a, const BlockMatrix& b) {
  if (a.rows != b.rows || a.start != b.start || a.col != b.col) return std::max<int64_t>(1, a.blocks());
  int64_t n = 0;
  for (size_t k = 0; k < a.val.size(); ++k) n += std::memcmp(&a.val[k], &b.val[k], sizeof(double)) != 0;
  return n;
}

Divided divided_cycle(int ranks, const MultigridSettings& ms) {
  int64_t counts[9] = {0, 0, 0, 0, -1, -1, 0, 0, 0};
  on_first_ranks(ranks, [&](MPI_Comm comm) {
    Simulation w(strip_scene(true), test_fabric(), quiet_run("mpi_self_contact_divided_" + std::to_string(ranks)), comm);
    Evaluator& ev = press(w);
    ev.evaluate(w.cloth.z.data(), nullptr);
    std::vector<double> diag(w.cloth.z.size());
    ev.stiffness_diagonal(w.cloth.z.data(), diag.data());
    const Reducer& red = w.red();
    RankRows rr;
    rr.number(red, w.tiling, w.lists.particles.items, w.cloth.grid.n());
    BlockMatrix mine, all;
    ev.assemble_stiffness(mine, &rr.column_of(), rr.size(), 1);
    rr.gather_matrix(red, mine, all);
    Multigrid mg(ms);
    mg.setup(all, rr.ids(), w.cloth.grid.ni, w.cloth.grid.nj, 1);
    DividedLevel dl;
    dl.plan(red, rr, mine, mg);
    dl.build(red, rr, mine, mg, true, true);
    const int64_t n = rr.size(), own = mine.rows;
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<double> b(size_t(3 * n)), x(size_t(3 * n)), want(size_t(3 * own)), b_mine(size_t(3 * own)),
        got(size_t(3 * own));
    for (double& v : b) v = u(rng);
    for (int64_t r = 0; r < own; ++r)
      for (int k = 0; k < 3; ++k) b_mine[3 * r + k] = b[3 * rr.mine()[r] + k];
    int64_t differ = 0;
    for (int round = 0; round < 2; ++round) {  // the second from the first's leftovers
      mg.apply(b.data(), x.data());
      rr.take_mine(x.data(), want.data());
      dl.apply(red, mine, mg, b_mine.data(), got.data());
      for (int64_t k = 0; k < 3 * own; ++k) differ += std::memcmp(&want[k], &got[k], sizeof(double)) != 0;
      for (double& v : b_mine) v *= -0.5;
      for (double& v : b) v *= -0.5;
    }
    counts[0] = red.sum_i64(differ);
    counts[1] = red.sum_i64(dl.ghosts());
    counts[2] = red.sum_i64(contact_ghost_blocks(mine, rr, ev.self_contact()));
    counts[3] = mg.levels();
    if (mg.finest_divisible()) {
      Multigrid md(ms);
      DividedLevel dd;
      const bool fresh = md.setup_points(rr.ids(), w.cloth.grid.ni, w.cloth.grid.nj, 1);
      dd.plan(red, rr, mine, md);
      dd.build(red, rr, mine, md, false, fresh);
      counts[4] = red.sum_i64(red.rank() == 0 ? matrix_differ(mg.matrix(1), md.matrix(1)) : 0);
      for (double& v : b) v *= 4;  // the first round's right-hand side
      mg.apply(b.data(), x.data());
      rr.take_mine(x.data(), want.data());
      for (int64_t r = 0; r < own; ++r)
        for (int k = 0; k < 3; ++k) b_mine[3 * r + k] = b[3 * rr.mine()[r] + k];
      dd.apply(red, mine, md, b_mine.data(), got.data());
      int64_t built = 0;
      for (int64_t k = 0; k < 3 * own; ++k) built += std::memcmp(&want[k], &got[k], sizeof(double)) != 0;
      counts[5] = red.sum_i64(built);
      const BlockMatrix& one = dd.level_one_rows();
      counts[6] = int64_t(red.max(double(dd.build_bytes() - 13 * rr.vector_bytes())));  // less the vectors
      counts[7] = int64_t(red.max(double(8 * md.matrix(1).rows + 76 * md.matrix(1).blocks())));
      counts[8] = int64_t(red.max(double(rr.matrix_bytes())));
      if (one.rows == 0) counts[5] += 1000000;  // a rank without level-1 rows covers nothing
    }
  });
  quiet_bcast(counts, 9, MPI_INT64_T);
  return {counts[0], counts[1], counts[2], counts[3], counts[4], counts[5], counts[6], counts[7], counts[8]};
}

// Chebyshev of degree 1 (the default: no product in the pre-smoother) and
// 3 (products and exchanges inside both sweeps), with the bilinear and the
// smoothed interpolation (whose restriction reads a wider ring of rows).
TEST(MpiSelfContact, DividedFinestLevelSameCycleOnTwoAndThreeRanks) {
  for (int degree : {1, 3})
    for (Interpolation ip : {Interpolation::Bilinear, Interpolation::Smoothed}) {
      MultigridSettings ms;
      ms.degree = degree;
      ms.interpolation = ip;
      ms.coarsest = 20;  // three levels at least on the strip
      const std::string label = "degree " + std::to_string(degree) + (ip == Interpolation::Bilinear ? ", bilinear" : ", smoothed");
      for (int ranks : {2, 3}) {
        const Divided d = divided_cycle(ranks, ms);
        EXPECT_GE(d.levels, 3) << label;
        EXPECT_GT(d.ghosts, 0) << label;
        EXPECT_GT(d.contact_blocks, 0) << label << ": no self-contact block reaches another rank";
        EXPECT_EQ(d.differ, 0) << label << ", " << ranks << " ranks: entries that differ from the whole cycle's";
        if (ip != Interpolation::Bilinear) continue;
        // Built from no K whole: level 1's operator and the cycle bitwise
        // the whole build's; gathered, level 1's rows and 13 vectors (the
        // cold power iteration's 12 steps and its start), well under K.
        EXPECT_EQ(d.level_one_differ, 0) << label << ", " << ranks << " ranks: level 1's operator differs";
        EXPECT_EQ(d.built_differ, 0) << label << ", " << ranks << " ranks: the cycle built from rows differs";
        EXPECT_GT(d.level_one_bytes, 0);
        EXPECT_LT(2 * d.level_one_bytes, d.whole_bytes) << label << ": level 1's rows are not well under K's";
        EXPECT_EQ(d.build_bytes, d.level_one_bytes) << label << ": gathered more than level 1's rows and 13 vectors";
      }
    }
}

}  // namespace
}  // namespace drape::test
