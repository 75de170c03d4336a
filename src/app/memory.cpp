#include "app/memory.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "decomp/collective.hpp"
#include "base/error.hpp"

namespace drape {

namespace {

constexpr int64_t kUnknown = std::numeric_limits<int64_t>::max();

// "Key:   123 kB" from a /proc file, in bytes (kUnknown if absent).
int64_t proc_kb(const char* file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key + ":", 0) == 0) {
      long long kb = 0;
      if (std::sscanf(line.c_str() + key.size() + 1, "%lld", &kb) == 1) return int64_t(kb) * 1024;
    }
  return kUnknown;
}

// A single number from a cgroup v2 file ("max" or absent: kUnknown).
int64_t cgroup_value(const std::string& file) {
  std::ifstream in(file);
  long long v = 0;
  return in >> v ? int64_t(v) : kUnknown;
}

// This process's cgroup v2 directory ("0::/path" in /proc/self/cgroup).
std::string cgroup_dir() {
  std::ifstream in("/proc/self/cgroup");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("0::", 0) == 0) return "/sys/fs/cgroup" + line.substr(3);
  return "";
}

// What is left under a limit, given the present use (both may be unknown).
int64_t headroom(int64_t limit, int64_t used) {
  if (limit == kUnknown) return kUnknown;
  return used == kUnknown ? limit : std::max<int64_t>(0, limit - used);
}

int64_t soft_limit(int resource) {
  rlimit r{};
  if (getrlimit(resource, &r) != 0 || r.rlim_cur == RLIM_INFINITY) return kUnknown;
  return int64_t(std::min<rlim_t>(r.rlim_cur, rlim_t(kUnknown)));
}

std::string gb(int64_t bytes) {
  std::ostringstream s;
  s.precision(bytes < 10e9 ? 2 : 3);
  s << 1e-9 * double(bytes);
  return s.str();
}

}  // namespace

int64_t estimated_bytes_per_rank(int64_t n, int ranks, bool nonlinear_cg) {
  // Measured peak RSS (report.json's peak_rss_bytes) of the default scene on
  // its finest mesh, 10 steps, one rank, 200x200 and 400x400: Newton 157.7
  // and 371.9 MB, i.e. 1785 bytes a particle over 86 MB (multigrid, AMRC and
  // grid sequencing within 62 bytes a particle of it); the nonlinear CG (or
  // the numeric gradient, which runs it) 168.4 and 415.6 MB, 2060 bytes over
  // 86 MB: its vectors are larger than Newton's. Rounded up, for a margin.
  // Of those, the arrays sized by the rank's lists (the evaluator's in list
  // order, Newton's compact vectors, the lists: 1168 of 1667 listed bytes a
  // particle at 1000 x 1000) fall with more ranks, and so do the nonlinear
  // CG's six vectors (384 bytes, in the compact order of the rank's own
  // unknowns); the cloth's, the residual and the vectors at z's positions
  // stay the grid's. A rank's lists are counted as 1.5 times its share of the
  // grid (METIS's imbalance, AMRC's rebalancing), at most the whole.
  const int64_t grid = nonlinear_cg ? 700 : 650, listed = nonlinear_cg ? 1400 : 1250;
  const int64_t fixed = int64_t(96) << 20;
  const double share = std::min(1.0, 1.5 / std::max(1, ranks));
  return fixed + grid * n + int64_t(double(listed) * share * double(n));
}

int64_t available_bytes() {
  const int64_t rss = proc_kb("/proc/self/status", "VmRSS");
  int64_t room = proc_kb("/proc/meminfo", "MemAvailable");
  // Address space and data segment count mappings, not only resident pages:
  // what is left under them is the limit less the present size.
  room = std::min(room, headroom(soft_limit(RLIMIT_AS), proc_kb("/proc/self/status", "VmSize")));
  room = std::min(room, headroom(soft_limit(RLIMIT_DATA), proc_kb("/proc/self/status", "VmData")));
  const std::string cg = cgroup_dir();
  if (!cg.empty())
    room = std::min(room, headroom(cgroup_value(cg + "/memory.max"), cgroup_value(cg + "/memory.current")));
  if (room == kUnknown) return kUnknown;
  return rss == kUnknown ? room : room + rss;
}

void check_memory(const Scene& scene, MPI_Comm comm) {
  const auto& p = scene.cloth.particles;
  const bool cg = scene.solver.method == SolverMethod::Cg || scene.solver.gradient == GradientMode::Numeric;
  const int64_t need = estimated_bytes_per_rank(int64_t(p[0]) * p[1], size_of(comm), cg);
  // The tightest rank decides for all (MiB fit an int up to 2 PiB).
  const int64_t mine = std::min<int64_t>(available_bytes() >> 20, std::numeric_limits<int>::max());
  const int64_t have = int64_t(-max_over_ranks(comm, -int(mine))) << 20;
  if (need <= have) return;
  throw InputError("cloth.particles = [" + std::to_string(p[0]) + ", " + std::to_string(p[1]) + "] needs about " +
                   gb(need) + " GB per rank, " + gb(have) +
                   " GB are available: use fewer particles or give each rank more memory (every rank holds "
                   "some arrays over the whole grid: more ranks lower it only in part)");
}

}  // namespace drape
