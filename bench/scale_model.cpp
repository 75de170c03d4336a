// The distributed design modelled to 1024 ranks (docs/performance.md, Scale
// study). For square cloths of the default scene's tile size, the tile graph
// with the program's METIS weights is partitioned into 1..1024 parts; per
// case: load imbalance, edge cut, what the halo exchange of every rank
// sends (halo_census: the same rule as HaloExchange), its neighbours, and the
// tiles a synthetic AMRC change moves (a diagonal band of folds refined by 2
// levels, rebalanced by the program's diffusion, METIS when that falls
// short). Under mpirun with 2 ranks a ping-pong measures latency and
// bandwidth here; with the compute time per particle and CG iteration
// (measured by bench_gradient, passed in), the time of a Newton-CG iteration
// is projected for strong and weak scaling. Partitions and counts are exact;
// iteration times are a model built on those measured inputs. On one rank,
// --alpha and --beta stand in for the ping-pong.
//   mpirun -n 2 scale_model [--sizes 1000,2000] [--parts 4,16] [--json FILE]
//                           [--product-seconds S --vector-seconds S]
//   scale_model [...] --alpha S --beta BYTES_PER_S
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <sstream>

#include "decomp/halo_census.hpp"
#include "decomp/migrate.hpp"
#include "decomp/partition.hpp"
#include "decomp/ping_pong.hpp"
#include "decomp/rebalance.hpp"
#include "io/config.hpp"
#include "io/json.hpp"
#include "io/kes.hpp"
#include "app/simulation.hpp"

namespace drape {
namespace {

// What one exchange sends per particle: a stiffness product (Newton's inner
// CG iteration) refreshes v's 3 positions; a gradient refreshes z's 8 values
// (positions and forces) and then the 3 residuals (evaluator: exchange(z,
// kAll), exchange_particles(rho, 3)).
constexpr int64_t kBytesPerCgIteration = 3 * sizeof(double);
constexpr int64_t kBytesPerGradient = (8 + 3) * sizeof(double);
// A tile 2 levels coarser than the finest carries a sixteenth of its work
// (a quarter of the particles, and of their elements, each way).
constexpr int64_t kCoarseDivisor = 16;

struct Settings {
  std::vector<int> sizes = {500, 1000, 2000, 4000, 8000, 16000};
  std::vector<int> parts = {1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024};
  double product_seconds = 0, vector_seconds = 0;  // per particle and CG iteration
  double alpha = 0, beta = 0;  // given, for a run without ping-pong
  std::string json;
};

// The finest mesh's work per tile (partition.hpp's tile_work) for an n x n
// cloth without allocating it: a tile's work depends only on whether it
// touches the cloth's borders, so a cloth of 3 x 3 tiles (the last ones as
// clipped as the large cloth's) has every kind, and each large tile takes
// the work of its kind.
std::vector<int64_t> fine_work(const Scene& base, const Tiling& tl) {
  // Along each side: up to 3 tiles as they are, else first, inner, last.
  auto kind = [](int k, int count) { return count <= 3 || k == 0 ? k : k == count - 1 ? 2 : 1; };
  auto side = [&](int n, int count) { return count <= 3 ? n : 2 * tl.t + (n - (count - 1) * tl.t); };
  Scene s = base;
  s.cloth.particles = {side(tl.ni, tl.nti), side(tl.nj, tl.ntj)};
  Simulation w(s, load_fabric(s.cloth.fabric));
  const std::vector<int64_t> each = tile_work(w.cloth, w.tiling);
  std::vector<int64_t> work(tl.count());
  for (int t = 0; t < tl.count(); ++t) {
    const int ki = kind(t / tl.ntj, tl.nti), kj = kind(t % tl.ntj, tl.ntj);
    work[t] = each[ki * w.tiling.ntj + kj];
  }
  return work;
}

// The kinds against tile_work over a whole cloth (small enough to hold).
constexpr int kCheckedSize = 512;
bool work_from_kinds_matches(const Scene& base, const Tiling& tl) {
  Scene s = base;
  s.cloth.particles = {tl.ni, tl.nj};
  Simulation w(s, load_fabric(s.cloth.fabric));
  return tile_work(w.cloth, w.tiling) == fine_work(base, tl);
}

struct Spread {
  double max = 0, mean = 0;
};
template <class T>
Spread spread(const std::vector<T>& v) {
  Spread s;
  for (T x : v) s.max = std::max(s.max, double(x)), s.mean += double(x);
  s.mean /= double(v.size());
  return s;
}

struct Migration {
  double imbalance_before = 1, imbalance_after = 1;
  double diffusion_reached = 1;  // what diffusion alone reached
  const char* method = "none";
  int tiles_moved = 0;
  int64_t bytes = 0, bytes_max_rank = 0;  // all ranks; the most one rank sends
};

// A band of folds along the diagonal (tiles within a twentieth of the side of
// it) refined by 2 levels on a mesh 2 levels coarser elsewhere; then the
// choice rebalance() makes: diffusion, METIS renamed to overlap the old parts
// only where diffusion stays above the threshold and METIS does better
// (partition_graph fills a part METIS leaves empty with a tile of the fullest).
Migration fold_band_migration(const Tiling& tl, const std::vector<int64_t>& fine, int parts, double threshold) {
  std::vector<int64_t> coarse(fine.size()), folded(fine.size());
  const int reach = std::max(1, tl.nti / 20);
  for (int t = 0; t < tl.count(); ++t) {
    coarse[t] = std::max<int64_t>(1, fine[t] / kCoarseDivisor);
    folded[t] = std::abs(t / tl.ntj - t % tl.ntj) <= reach ? fine[t] : coarse[t];
  }
  const std::vector<int> before = partition_graph(tl, coarse, parts).owner;
  Migration m;
  m.imbalance_before = m.imbalance_after = partition_with(tl, before, folded, parts).imbalance;
  m.diffusion_reached = m.imbalance_before;
  if (parts == 1 || m.imbalance_before <= threshold) return m;
  std::vector<int> after = diffuse_tiles(tl, before, folded, parts, threshold);
  double best = partition_with(tl, after, folded, parts).imbalance;
  m.diffusion_reached = best;
  m.method = "diffusion";
  if (best > threshold) {
    const Partition fresh = partition_graph(tl, folded, parts);
    if (fresh.imbalance < best) {
      after = relabel_to_overlap(before, fresh.owner, folded, parts);
      best = fresh.imbalance;
      m.method = "metis";
    }
  }
  if (!(best < m.imbalance_before)) {
    m.method = "none";
    return m;
  }
  m.imbalance_after = best;
  std::vector<int64_t> sent(parts, 0);
  for (int t = 0; t < tl.count(); ++t)
    if (before[t] != after[t]) {
      ++m.tiles_moved;
      m.bytes += tile_migration_bytes(tl, t);
      sent[before[t]] += tile_migration_bytes(tl, t);
    }
  m.bytes_max_rank = *std::max_element(sent.begin(), sent.end());
  return m;
}

struct Network {
  double alpha = 0, beta = 0;  // s; bytes/s
  bool measured() const { return alpha > 0 && beta > 0; }
};

// The modelled seconds of one Newton-CG iteration on the slowest rank: its
// share of the stiffness product and vector passes, one message per
// neighbour and its bytes, then 2 allreduces of log2(P) latencies each.
double iteration_seconds(const Settings& st, const Network& net, int64_t particles, const Partition& p,
                         const HaloCensus& h) {
  const double per_particle = st.product_seconds + st.vector_seconds;
  int64_t total = 0;
  for (int64_t w : p.work) total += w;
  double slowest = 0;
  for (size_t r = 0; r < p.work.size(); ++r) {
    const double compute = per_particle * double(particles) * double(p.work[r]) / double(total);
    const double bytes = double(std::max(h.sent[r], h.received[r]) * kBytesPerCgIteration);
    slowest = std::max(slowest, compute + h.neighbours[r] * net.alpha + bytes / net.beta);
  }
  const int parts = int(p.work.size());
  return slowest + 2 * std::ceil(std::log2(double(parts))) * net.alpha;
}

void write_case(Json& j, const Tiling& tl, const Partition& p, const HaloCensus& h, const Migration& m,
                double seconds) {
  const int parts = int(p.work.size());
  std::vector<int64_t> owned(parts, 0), tiles(parts, 0);
  for (int t = 0; t < tl.count(); ++t) {
    const TileRange r = tl.range(t);
    owned[p.owner[t]] += int64_t(r.i1 - r.i0) * (r.j1 - r.j0);
    ++tiles[p.owner[t]];
  }
  std::vector<int64_t> cg_bytes(parts), grad_bytes(parts);
  for (int r = 0; r < parts; ++r) {
    cg_bytes[r] = h.sent[r] * kBytesPerCgIteration;
    grad_bytes[r] = h.sent[r] * kBytesPerGradient;
  }
  auto both = [&](const char* key, Spread s) {
    j.begin_object(key).value("max", s.max).value("mean", s.mean).end_object();
  };
  j.begin_object();
  j.value("size", tl.ni).value("particles", (long long)tl.ni * tl.nj).value("tiles", tl.count());
  j.value("parts", parts).value("imbalance", p.imbalance).value("edge_cut", (long long)p.edge_cut);
  both("tiles_per_rank", spread(tiles));
  long long tile_sum = 0;
  for (int64_t k : tiles) tile_sum += k;
  j.value("tiles_in_parts", tile_sum);
  // partition_graph leaves no part without a tile (checked by tests/scale_model.sh).
  j.value("parts_without_tiles", int(std::count(tiles.begin(), tiles.end(), int64_t(0))));
  both("owned_particles", spread(owned));
  both("ghost_particles", spread(h.received));
  both("sent_particles", spread(h.sent));
  both("halo_bytes_cg_iteration", spread(cg_bytes));
  both("halo_bytes_gradient", spread(grad_bytes));
  both("neighbours", spread(h.neighbours));
  j.begin_object("fold_band_migration")
      .value("imbalance_before", m.imbalance_before)
      .value("imbalance_after", m.imbalance_after)
      .value("diffusion_reached", m.diffusion_reached)
      .value("method", m.method)
      .value("tiles_moved", m.tiles_moved)
      .value("bytes", (long long)m.bytes)
      .value("bytes_max_rank", (long long)m.bytes_max_rank)
      .end_object();
  if (seconds > 0) j.value("iteration_seconds_modelled", seconds);
  j.end_object();
}

// Every case, as one JSON document; progress on stderr.
std::string model(const Settings& st, const Network& net, const PingPong* pp) {
  const Scene base = load_scene(std::nullopt, {});
  const int tile = base.cloth.tile;
  const double threshold = base.parallel.imbalance;
  Json j;
  j.begin_object();
  j.value("measured", pp ? "alpha and beta: ping-pong between 2 ranks here; compute seconds per particle: given "
                             "(run/scale_study measures them with bench_gradient)"
                           : "alpha and beta given (no ping-pong); compute seconds per particle given");
  j.value("modelled", "partitions, halo and migration counts are exact for the design; "
                      "iteration times are a latency-bandwidth model");
  j.value("tile", tile).value("imbalance_threshold", threshold);
  j.value("bytes_per_particle_cg_iteration", (long long)kBytesPerCgIteration);
  j.value("bytes_per_particle_gradient", (long long)kBytesPerGradient);
  j.value("product_seconds_per_particle", st.product_seconds);
  j.value("vector_seconds_per_particle", st.vector_seconds);
  if (pp) {
    j.begin_object("ping_pong").value("alpha_seconds", pp->alpha).value("beta_bytes_per_second", pp->beta);
    j.begin_array("sizes");
    for (size_t k = 0; k < pp->bytes.size(); ++k)
      j.begin_object().value("bytes", (long long)pp->bytes[k]).value("seconds", pp->seconds[k]).end_object();
    j.end_array().end_object();
  }
  const bool project = net.measured() && st.product_seconds > 0;
  j.value("alpha_seconds", net.alpha).value("beta_bytes_per_second", net.beta);
  for (int n : st.sizes)
    if (n <= kCheckedSize) {
      j.value("work_from_tile_kinds_matches", work_from_kinds_matches(base, Tiling(n, n, tile)));
      break;
    }
  j.begin_array("cases");
  for (int n : st.sizes) {
    const Tiling tl(n, n, tile);
    const std::vector<int64_t> work = fine_work(base, tl);
    for (int parts : st.parts) {
      if (parts > tl.count()) {
        std::fprintf(stderr, "%d x %d: %d parts skipped (only %d tiles)\n", n, n, parts, tl.count());
        continue;
      }
      const Partition p = partition_graph(tl, work, parts);
      const HaloCensus h = halo_census(tl, p.owner, parts);
      const Migration m = fold_band_migration(tl, work, parts, threshold);
      const double s = project ? iteration_seconds(st, net, int64_t(n) * n, p, h) : 0;
      write_case(j, tl, p, h, m, s);
      std::fprintf(stderr, "%d x %d, %d parts: imbalance %.3f, halo max %.0f bytes, migration %s %d tiles\n", n,
                   n, parts, p.imbalance, double(*std::max_element(h.sent.begin(), h.sent.end())) *
                   kBytesPerCgIteration, m.method, m.tiles_moved);
    }
  }
  j.end_array();
  j.end_object();
  return j.str();
}

}  // namespace
}  // namespace drape

int main(int argc, char** argv) {
  using namespace drape;
  int provided = 0, rank = 0, ranks = 1;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  Settings st;
  CLI::App app{"scale_model: partitions, halos and migration to 1024 ranks, and a latency-bandwidth "
               "projection"};
  app.option_defaults()->always_capture_default();
  app.add_option("--sizes", st.sizes, "particles per side of each square cloth")->delimiter(',')
      ->check(CLI::Range(2, 100000));
  app.add_option("--parts", st.parts, "part counts (ranks)")->delimiter(',')->check(CLI::Range(1, 1 << 20));
  app.add_option("--product-seconds", st.product_seconds, "one stiffness product, seconds per particle")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--vector-seconds", st.vector_seconds,
                 "one CG iteration's vector passes, seconds per particle")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--alpha", st.alpha, "latency, s, where no ping-pong runs (one rank)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--beta", st.beta, "bandwidth, bytes/s, where no ping-pong runs (one rank)")
      ->check(CLI::Range(0.0, 1e15));
  app.add_option("--json", st.json, "write the figures here (default: stdout, where METIS may print too)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::ostringstream quiet;
    const int code = (rank == 0 ? app.exit(e) : app.exit(e, quiet, quiet)) == 0 ? 0 : 2;
    MPI_Finalize();
    return code;
  }
  std::optional<PingPong> pp;
  Network net{st.alpha, st.beta};
  if (ranks >= 2) {
    pp = ping_pong(MPI_COMM_WORLD);
    net = {pp->alpha, pp->beta};
  }
  int code = 0;
  if (rank == 0) {
    try {
      const std::string out = model(st, net, pp ? &*pp : nullptr);
      if (st.json.empty()) {
        std::printf("%s\n", out.c_str());
      } else {
        std::ofstream(st.json) << out << '\n';
        std::fprintf(stderr, "wrote %s\n", st.json.c_str());
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "scale_model: %s\n", e.what());
      code = 1;
    }
  }
  MPI_Finalize();
  return code;
}
