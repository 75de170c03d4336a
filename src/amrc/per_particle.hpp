#pragma once
// The criterion's per-particle fields over ranks (amrc.cpp, near.cpp).
#include <vector>

#include "amrc/amrc.hpp"

namespace drape {

// Runs at(p) on every particle of the rank's tiles (all of them on one
// rank), then takes each particle's bits from its owner (an or over the
// ranks: the others hold 0 there).
template <class At>
void per_particle(const Cloth& c, const AdaptShare& share, std::vector<uint32_t>& out, At&& at) {
  const int64_t n = c.grid.n();
  out.assign(n, 0);
  if (!share.tiling) {
#pragma omp parallel for schedule(static)
    for (int64_t p = 0; p < n; ++p) out[p] = at(p);
    return;
  }
  const Tiling& tl = *share.tiling;
  const std::vector<int>& tiles = *share.tiles;
#pragma omp parallel for schedule(dynamic, 1)
  for (size_t k = 0; k < tiles.size(); ++k) {
    const TileRange r = tl.range(tiles[k]);
    for (int i = r.i0; i < r.i1; ++i)
      for (int j = r.j0; j < r.j1; ++j) out[int64_t(i) * tl.nj + j] = at(int64_t(i) * tl.nj + j);
  }
  share.reducer->or_each(out.data(), n);
}

}  // namespace drape
