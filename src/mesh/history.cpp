// A rank's step history (x1, x2) for the particles it holds only.
#include <limits>
#include <stdexcept>

#include "mesh/cloth.hpp"

namespace drape {

std::vector<int64_t> held_particles(const Cloth& c) {
  std::vector<int64_t> held;
  for (int64_t p = 0; p < c.grid.n(); ++p)
    if (c.holds(p)) held.push_back(p);
  return held;
}

void hold_history(Cloth& c, const std::vector<int64_t>& held) {
  if (held.size() > size_t(std::numeric_limits<int32_t>::max() / 3))
    throw std::length_error("hold_history: more particles than 32-bit slots reach");
  std::vector<int32_t> slot(size_t(c.grid.n()), -1);
  std::vector<double> x1(3 * held.size(), 0.0), x2(3 * held.size(), 0.0);
  for (size_t s = 0; s < held.size(); ++s) {
    const int64_t p = held[s];
    slot[size_t(p)] = int32_t(s);
    if (!c.holds(p)) continue;
    for (int k = 0; k < 3; ++k) {
      x1[3 * s + k] = c.x1_at(p)[k];
      x2[3 * s + k] = c.x2_at(p)[k];
    }
  }
  c.slot_of.swap(slot);
  c.x1.swap(x1);
  c.x2.swap(x2);
  ++c.held_version;
}

}  // namespace drape
