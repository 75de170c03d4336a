// The paper's Table 2 and Fig. 8 on the machine at hand: a fixed number of
// CG iterations (the paper's method) on a 1000 x 1000 cloth mid-drape, for
// each schedule at 1..N threads, all in one process so the ratios come from
// one run. Prints a table and writes JSON (run/scaling draws the plot).
//   scaling [--size 1000] [--iterations 100] [--threads N | --thread-counts 1,2,4,...] [--repeat R]
//           [--amrc 0|1] [--out scaling.json]
// --amrc 1: on an uneven AMRC mesh (coarse, with a finest band along a fold),
// where the tiles' work differs and the schedules differ most.
// With R > 1 every configuration is timed R times, interleaved (round after
// round over all of them, so drift on a shared machine hits all alike), and
// the median is reported.
#include <omp.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "io/json.hpp"
#include "mid_drape.hpp"
#include "solver/checksum.hpp"

namespace drape {
namespace {

struct Row {
  std::string schedule;
  int threads;
  double seconds, speedup, karp_flatt, parallel_overhead, gradient, loops, balance;
};

// One timed run's figures: the whole, the gradient's part, and the parallel
// loops' wall time and balance (busy thread-seconds / (wall x threads): 1 when
// no thread waits at a loop's end, which is what the schedules differ in).
struct Timing {
  double seconds = 0, gradient = 0, loops = 0, balance = 0;
};

// One cloth for every configuration, made once (at the most threads, so
// that what is sized by the thread count fits them all): each run starts
// from its saved state, with the active lists' learned cuts dropped, as a
// cloth made anew would. Every run must end in the same state, bit for bit
// (the results do not depend on threads or schedule): `checksum` says so.
struct Bed {
  Simulation w;
  std::vector<double> z0;
  double first_step;
  Bed(int n, bool amrc) : w(mid_drape_scene(n), load_fabric("denim-A")) {
    if (amrc) uneven_amrc_mesh(w);
    jitter_mid_drape(w, 7);
    z0 = w.cloth.z;
    first_step = w.loop->minimizer().first_step();
  }
  void restore(Schedule sc) {
    w.policy.schedule = sc;
    std::copy(z0.begin(), z0.end(), w.cloth.z.begin());
    w.loop->minimizer().set_first_step(first_step);
    for (const ActiveList* l : {&w.lists.particles, &w.lists.edges, &w.lists.triples, &w.lists.shears})
      l->cuts.clear();
  }
};

Timing run_once(Bed& bed, int iterations, Schedule sc, int threads, std::string& checksum) {
  omp_set_num_threads(threads);
  bed.restore(sc);
  TimeLoop& loop = *bed.w.loop;
  Cloth& cloth = bed.w.cloth;
  CgSettings cs;
  cs.max_iterations = iterations;
  cs.tolerance = 0;
  cs.free_particles = loop.free_particles();
  Timers tm;
  const LoopClock c0 = loop_clock();
  const auto t0 = std::chrono::steady_clock::now();
  loop.minimizer().minimize(loop.evaluator(), cloth.z.data(), cs, tm);
  Timing r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.gradient = tm.seconds[kGradient] + tm.seconds[kLineSearch];
  r.loops = loop_clock().wall - c0.wall;
  r.balance = r.loops > 0 ? (loop_clock().busy - c0.busy) / (r.loops * threads) : 1.0;
  checksum = state_checksum(cloth, bed.w.tiling, bed.w.owned(), bed.w.red()).hex();
  return r;
}

}  // namespace
}  // namespace drape

int main(int argc, char** argv) {
  using namespace drape;
  int n = 1000, iterations = 100, max_threads = omp_get_num_procs(), repeat = 1;
  bool amrc = false;
  std::string out = "scaling.json";
  CLI::App app{"scaling: the paper's Table 2 / Fig. 8, each schedule at 1..N threads"};
  app.option_defaults()->always_capture_default();
  app.add_option("--size", n, "particles per side")->check(CLI::Range(9, 100000));
  app.add_option("--iterations", iterations, "CG iterations per configuration")->check(CLI::Range(1, 1000000));
  std::vector<int> counts;  // the thread counts run; 1..max_threads by default
  app.add_option("--threads", max_threads, "up to this many threads")->check(CLI::Range(1, 1024));
  app.add_option("--thread-counts", counts, "only these thread counts, from 1 up (e.g. 1,2,4,8,16)")
      ->delimiter(',')
      ->check(CLI::Range(1, 1024));
  app.add_option("--repeat", repeat, "rounds, interleaved; the median is reported")->check(CLI::Range(1, 1000));
  app.add_option("--amrc", amrc, "1: on an uneven AMRC mesh");
  app.add_option("--out", out, "JSON file to write");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help: 0; a bad flag: its message and 2
  }
  if (counts.empty())
    for (int p = 1; p <= max_threads; ++p) counts.push_back(p);
  if (counts[0] != 1 || !std::is_sorted(counts.begin(), counts.end())) {
    std::fprintf(stderr, "scaling: --thread-counts must start at 1 and rise (the speed-up is against 1)\n");
    return 2;
  }
  const int nc = static_cast<int>(counts.size());
  const Schedule schedules[] = {Schedule::ActiveLists, Schedule::Static, Schedule::Dynamic, Schedule::Guided};
  // times[schedule][c] (thread count counts[c]) over the rounds
  std::vector<std::vector<std::vector<double>>> times(4, std::vector<std::vector<double>>(nc));
  std::vector<std::vector<std::vector<double>>> grads = times, loops = times, balance = times;
  omp_set_num_threads(counts.back());
  Bed bed(n, amrc);
  std::string first_checksum;
  for (int r = 0; r < repeat; ++r)
    for (int si = 0; si < 4; ++si)
      for (int c = 0; c < nc; ++c) {
        const int p = counts[c];
        std::string checksum;
        const Timing t = run_once(bed, iterations, schedules[si], p, checksum);
        if (first_checksum.empty()) first_checksum = checksum;
        if (checksum != first_checksum) {
          std::fprintf(stderr, "scaling: %s at %d thread(s) ended in state %s, not %s: the runs are not alike\n",
                       to_string(schedules[si]), p, checksum.c_str(), first_checksum.c_str());
          return 1;
        }
        times[si][c].push_back(t.seconds);
        grads[si][c].push_back(t.gradient);
        loops[si][c].push_back(t.loops);
        balance[si][c].push_back(t.balance);
        std::fprintf(stderr, "round %d/%d %s %d thread(s): %.3f s, loops %.3f s, balance %.3f\n", r + 1,
                     repeat, to_string(schedules[si]), p, t.seconds, t.loops, t.balance);
      }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
  };
  std::vector<Row> rows;
  std::printf("%-13s %7s %10s %8s %10s %12s %10s %10s %8s\n", "schedule", "threads", "time [s]", "speed-up",
              "seq. frac", "par. ovh [s]", "grad [s]", "loops [s]", "balance");
  for (int si = 0; si < 4; ++si) {
    const double t1 = median(times[si][0]);
    for (int c = 0; c < nc; ++c) {
      const int p = counts[c];
      const double t = median(times[si][c]), grad = median(grads[si][c]);
      const double lw = median(loops[si][c]), bal = median(balance[si][c]);
      const double sp = t1 / t;
      // Karp-Flatt: the serial fraction implied by the measured speed-up.
      const double e = p > 1 ? (1 / sp - 1.0 / p) / (1 - 1.0 / p) : 0.0;
      const double ovh = t - t1 / p;  // time beyond perfect division
      rows.push_back({to_string(schedules[si]), p, t, sp, e, ovh, grad, lw, bal});
      std::printf("%-13s %7d %10.3f %8.2f %10.3f %12.3f %10.3f %10.3f %8.3f\n", to_string(schedules[si]), p,
                  t, sp, e, ovh, grad, lw, bal);
    }
  }
  Json j;
  j.begin_object();
  j.value("particles", (long long)n * n);
  j.value("iterations", iterations);
  j.value("method", "cg");
  j.value("amrc", amrc);
  j.value("repeat", repeat);
  j.begin_array("rows");
  for (const Row& r : rows)
    j.begin_object()
        .value("schedule", r.schedule)
        .value("threads", r.threads)
        .value("seconds", r.seconds)
        .value("speedup", r.speedup)
        .value("serial_fraction", r.karp_flatt)
        .value("parallel_overhead_seconds", r.parallel_overhead)
        .value("gradient_seconds", r.gradient)
        .value("loop_seconds", r.loops)
        .value("loop_balance", r.balance)
        .end_object();
  j.end_array();
  j.end_object();
  std::ofstream(out) << j.str() << "\n";
  return 0;
}
