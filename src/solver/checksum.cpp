#include "solver/checksum.hpp"

#include <cstdio>

#include "mesh/tiles.hpp"

namespace drape {

namespace {

uint64_t particle_hash(const Cloth& c, int64_t p, uint64_t seed) {
  Hasher h(seed ^ uint64_t(p));
  for (int k = 0; k < 3; ++k) h.add(c.x()[3 * p + k]);
  for (int d = 0; d < 2; ++d) {
    h.add(c.force(0, 2 * p + d));
    h.add(c.force(1, 2 * p + d));
  }
  h.add(c.force(2, p));
  h.add(uint64_t(c.flags[p]));
  h.add(uint64_t(c.level[p]));
  return h.value();
}

}  // namespace

std::string Checksum::hex() const {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%016llx%016llx", (unsigned long long)lane[0],
                (unsigned long long)lane[1]);
  return buf;
}

Checksum state_checksum(const Cloth& c, const Tiling& tiling, const std::vector<int>& tiles,
                        const Reducer& red) {
  uint64_t s0 = 0, s1 = 0;
  const int nt = int(tiles.size());
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : s0, s1)
  for (int t = 0; t < nt; ++t) {
    const TileRange r = tiling.range(tiles[t]);
    for (int i = r.i0; i < r.i1; ++i)
      for (int j = r.j0; j < r.j1; ++j) {
        const int64_t p = c.grid.id(i, j);
        s0 += particle_hash(c, p, 0x243f6a8885a308d3ULL);
        s1 += particle_hash(c, p, 0x13198a2e03707344ULL);
      }
  }
  Checksum out;
  out.lane[0] = red.sum_u64(s0);
  out.lane[1] = red.sum_u64(s1);
  return out;
}

}  // namespace drape
