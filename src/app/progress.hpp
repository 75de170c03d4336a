#pragma once
// Progress lines on rank 0: one per step (at most every half second), and
// during a long step one per couple of seconds with the iteration and cost;
// the ETA extrapolates the mean wall time per step.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>

#include "solver/time_loop.hpp"

namespace drape {

class Progress {
 public:
  // wall_limit > 0: the run ends after that many seconds at the latest.
  // first: the step the run starts after (a restart's checkpoint step).
  Progress(bool on, int steps, double wall_limit = 0, int first = 0)
      : on_(on), steps_(steps), first_(first), limit_(wall_limit), start_(clock::now()), last_(start_) {}

  void iteration(int step, int it, double cost) {
    if (!on_) return;
    const auto now = clock::now();
    if (seconds(last_, now) < 2.0) return;
    last_ = now;
    std::printf("  step %d  iteration %d  cost %.4e  (%.0f s)\n", step, it, cost, seconds(start_, now));
    std::fflush(stdout);
  }

  // particles >= 0: the mesh changes (AMRC, grid sequencing), show its size.
  void step(const StepStats& st, int64_t particles = -1) {
    if (!on_) return;
    const auto now = clock::now();
    const double el = seconds(start_, now);
    if (seconds(last_, now) < 0.5 && st.step != steps_ && st.step > first_ + 1) return;
    last_ = now;
    double eta = el / std::max(1, st.step - first_) * (steps_ - st.step);
    if (limit_ > 0) eta = std::min(eta, std::max(0.0, limit_ - el));
    char mesh[40] = "";
    if (particles >= 0) std::snprintf(mesh, sizeof mesh, "  particles %lld", (long long)particles);
    std::printf("step %5d/%d  t %.4f s  dt %.3g ms  iterations %4d%s  cost %.4e  speed %.3g m/s%s  ETA %s\n",
                st.step, steps_, st.time, st.dt * 1e3, st.iterations, st.converged ? "" : " (max)",
                st.cost.total(), st.max_speed, mesh, clock_text(eta).c_str());
    std::fflush(stdout);
  }

  // What the run solved, for the closing line.
  struct Solved {
    const char* method = "";
    const char* preconditioner = "";
    int level = 0;              // grid sequencing: the final mesh's level (0: the finest grid)
    long long particles = 0;    // unknown particles of the final mesh, all ranks
    double spacing = 0;         // m, the final mesh's
    int ni = 0, nj = 0;         // the finest grid
    long long unconverged = 0;  // steps that ended at the iteration limit
    double written = 0;         // m, the deepest penetration of the surface as written
    long long projections = 0;  // particles the safety net set back on a surface
  };

  // The closing line: the time, the state, and what was solved; it names
  // the mesh when the run ended on a coarser one than the grid.
  void finish(bool at_rest, double penetration, double zigzag_share, const Solved& s) {
    if (!on_) return;
    std::string mesh;
    if (s.level > 0) {
      char b[160];
      std::snprintf(b, sizeof b, " on the level-%d mesh (%lld particles solved, spacing %.3g mm; the grid is %d x %d)",
                    s.level, s.particles, 1e3 * s.spacing, s.ni, s.nj);
      mesh = b;
    }
    const std::string pre = std::string(s.preconditioner) == "none" ? std::string("no preconditioner")
                                                                     : std::string(s.preconditioner) + " preconditioner";
    std::printf("done in %s: cloth %s%s, %s with %s, deepest penetration %.3g m",
                clock_text(seconds(start_, clock::now())).c_str(), at_rest ? "at rest" : "still moving",
                mesh.c_str(), s.method, pre.c_str(), penetration);
    // Where they differ, the surface filled in between coarse particles cut
    // an obstacle; projections mean the contact layer let particles through.
    if (s.written != penetration) std::printf(" (%.3g m on the surface as written)", s.written);
    if (s.projections > 0) std::printf(", %lld particle(s) set back on a surface by the safety net", s.projections);
    if (s.unconverged > 0) std::printf(", %lld unconverged step(s)", s.unconverged);
    std::printf("\n");
    // A few kinks are folds caught between particles; many mean the mesh
    // spacing itself shapes the drape (see solver/zigzag.hpp).
    if (zigzag_share > 0.05)
      std::printf("note: %.1f %% of the mesh lines' neighbouring turns zigzag (kinks at the mesh spacing):\n"
                  "      there the shape depends on the mesh, and a finer one will differ\n",
                  100 * zigzag_share);
  }

 private:
  using clock = std::chrono::steady_clock;
  static double seconds(clock::time_point a, clock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
  }
  static std::string clock_text(double s) {
    char b[32];
    const int t = int(s + 0.5);
    if (t >= 3600) std::snprintf(b, sizeof b, "%dh%02dm", t / 3600, (t / 60) % 60);
    else std::snprintf(b, sizeof b, "%dm%02ds", t / 60, t % 60);
    return b;
  }
  bool on_;
  int steps_, first_;
  double limit_;
  clock::time_point start_, last_;
};

}  // namespace drape
