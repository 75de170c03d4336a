#pragma once
// The state checksum (docs/design.md §4): every particle's positions, element forces
// and flags are hashed together with its global id, and the hashes summed
// (mod 2^64, two independent lanes). A sum is the same in any order, so the
// digest identifies the state however the particles were split over ranks,
// threads and tiles.
#include <cstdint>
#include <cstring>
#include <string>

#include "mesh/cloth.hpp"
#include "mesh/tiles.hpp"
#include "solver/reducer.hpp"

namespace drape {

// The hash both digests are built from: splitmix64's finaliser applied to a
// running value (a change in any input bit changes the result).
class Hasher {
 public:
  explicit Hasher(uint64_t seed) : h_(mix(seed)) {}
  void add(uint64_t v) { h_ = mix(h_ ^ (v + 0x9e3779b97f4a7c15ULL)); }
  void add(double v) {
    uint64_t u;
    std::memcpy(&u, &v, sizeof u);
    add(u);
  }
  void add(const std::string& s) {
    add(uint64_t(s.size()));
    for (unsigned char ch : s) add(uint64_t(ch));
  }
  uint64_t value() const { return h_; }
  static uint64_t mix(uint64_t h) {
    h ^= h >> 30;
    h *= 0xbf58476d1ce4e5b9ULL;
    h ^= h >> 27;
    h *= 0x94d049bb133111ebULL;
    h ^= h >> 31;
    return h;
  }

 private:
  uint64_t h_;
};

struct Checksum {
  uint64_t lane[2] = {0, 0};
  std::string hex() const;
};

// Sums over the particles of the given tiles; the reducer adds the ranks.
Checksum state_checksum(const Cloth& c, const Tiling& tiling, const std::vector<int>& tiles,
                        const Reducer& red);

}  // namespace drape
