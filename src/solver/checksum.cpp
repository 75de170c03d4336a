#include "solver/checksum.hpp"

#include <cstdio>
#include <cstring>

#include "decomp/tiles.hpp"

namespace drape {

namespace {

inline uint64_t mix(uint64_t h) {  // splitmix64 finaliser
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ULL;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebULL;
  h ^= h >> 31;
  return h;
}

inline uint64_t bits(double v) {
  uint64_t u;
  std::memcpy(&u, &v, sizeof u);
  return u;
}

uint64_t particle_hash(const Cloth& c, int64_t p, uint64_t seed) {
  uint64_t h = mix(seed ^ uint64_t(p));
  auto add = [&](uint64_t v) { h = mix(h ^ (v + 0x9e3779b97f4a7c15ULL)); };
  for (int k = 0; k < 3; ++k) add(bits(c.x()[3 * p + k]));
  for (int d = 0; d < 2; ++d) {
    add(bits(c.tension()[2 * p + d]));
    add(bits(c.moment()[2 * p + d]));
  }
  add(bits(c.shear()[p]));
  add(c.flags[p]);
  add(c.level[p]);
  return h;
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
