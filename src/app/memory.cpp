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

int64_t estimated_bytes_per_rank(const Scene& scene, int ranks) {
  // Fitted to one case, the box drape at 1000 x 1000 on its finest mesh (2
  // steps, one thread a rank; peak RSS per rank from /usr/bin/time) on 1, 2,
  // 4 and 8 ranks: Newton 1.20, 0.67, 0.37, 0.23 GB; the nonlinear CG 1.47,
  // 0.81, 0.45, 0.28 GB. As a + b/P: b, the arrays a rank holds for its own
  // tiles (its lists, the evaluator's and the solvers' arrays, the cloth's in
  // slots), 1109 (CG 1360) bytes a particle; a, what every rank holds, the
  // process's own ~30 MB and the arrays laid out over the whole grid (z's
  // positions, flags, levels, the slot map; the CG's gradient residual),
  // 61 (80) bytes a particle. With amrc.enabled (self-contact on), 1 and 4
  // ranks: 1.24, 0.45 GB, a at 164 bytes a particle: AMRC's tree and
  // criterion bits and the near-sheet search's room are the grid's too. Each
  // term rounded up; a rank's lists counted at 1.5 times its share of the
  // grid (METIS's imbalance, AMRC's rebalancing), at most the whole. Not
  // counted: the multigrid's K and levels, built once the cloth touches
  // something (docs/performance.md, Memory: most of a landed run's bytes).
  const bool cg = scene.solver.method == SolverMethod::Cg || scene.solver.gradient == GradientMode::Numeric;
  const auto& p = scene.cloth.particles;
  const int64_t n = int64_t(p[0]) * p[1];
  int64_t grid = cg ? 95 : 70;
  if (scene.amrc.enabled || scene.amrc.start_spacing > 0) grid += 35;  // the tree, the criterion's bits
  if (scene.amrc.enabled && scene.solver.self_contact) grid += 75;      // near-sheet search's room
  const int64_t listed = cg ? 1500 : 1250;
  const int64_t fixed = int64_t(64) << 20;
  const double share = std::min(1.0, 1.5 / std::max(1, ranks));
  return fixed + grid * n + int64_t(double(listed) * share * double(n));
}

MemoryRoom available_room() {
  const int64_t rss = proc_kb("/proc/self/status", "VmRSS");
  auto plus_rss = [rss](int64_t room) { return room == kUnknown || rss == kUnknown ? room : room + rss; };
  // Address space and data segment count mappings, not only resident pages:
  // what is left under them is the limit less the present size.
  const int64_t process = std::min(headroom(soft_limit(RLIMIT_AS), proc_kb("/proc/self/status", "VmSize")),
                                   headroom(soft_limit(RLIMIT_DATA), proc_kb("/proc/self/status", "VmData")));
  int64_t node = proc_kb("/proc/meminfo", "MemAvailable");
  const std::string cg = cgroup_dir();
  if (!cg.empty())
    node = std::min(node, headroom(cgroup_value(cg + "/memory.max"), cgroup_value(cg + "/memory.current")));
  return {plus_rss(process), plus_rss(node)};
}

void check_memory(const Scene& scene, MPI_Comm comm) {
  const auto& p = scene.cloth.particles;
  const int64_t need = estimated_bytes_per_rank(scene, size_of(comm));
  // A process's limits are its own; the node's memory (and a cgroup's) its
  // ranks share. In MiB (an int reaches 2 PiB).
  const int sharing = ranks_on_node(comm);
  const MemoryRoom room = available_room();
  auto mib = [](int64_t b) { return std::min<int64_t>(b >> 20, std::numeric_limits<int>::max()); };
  const int64_t mine = std::min(mib(room.process), mib(room.node) / sharing);  // this rank's part
  const bool short_here = mib(need) > mine;
  if (max_over_ranks(comm, short_here ? 1 : 0) == 0) return;
  const int64_t have = int64_t(-max_over_ranks(comm, -int(mine))) << 20;  // the tightest rank's
  const int most = max_over_ranks(comm, sharing);
  throw InputError("cloth.particles = [" + std::to_string(p[0]) + ", " + std::to_string(p[1]) + "] needs about " +
                   gb(need) + " GB per rank, " + gb(have) + " GB are available" +
                   (most > 1 ? " to each of the " + std::to_string(most) + " ranks sharing a node" : "") +
                   ": use fewer particles or give each rank more memory (every rank holds "
                   "some arrays over the whole grid: more ranks lower it only in part)");
}

}  // namespace drape
