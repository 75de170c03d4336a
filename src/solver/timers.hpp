#pragma once
// Seconds spent per phase of a run (the paper's Table 2 breakdown).
#include <chrono>

namespace drape {

enum Phase {
  kSetup, kGradient, kLineSearch, kVector, kScaling, kAmrc, kLists, kMigrate, kOutput, kPrecondition, kPhases
};
inline const char* phase_name(int p) {
  static const char* names[] = {"setup", "gradient",     "line_search", "vector_updates", "scaling",
                                "amrc",  "list_rebuild", "migration",   "output",         "precondition"};
  return names[p];
}

struct Timers {
  double seconds[kPhases] = {};
  double total() const {
    double s = 0;
    for (double v : seconds) s += v;
    return s;
  }
};

// Adds the lifetime of the scope to one phase.
class ScopedPhase {
 public:
  ScopedPhase(Timers& t, Phase p) : t_(t), p_(p), start_(std::chrono::steady_clock::now()) {}
  ~ScopedPhase() {
    t_.seconds[p_] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  Timers& t_;
  Phase p_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace drape
