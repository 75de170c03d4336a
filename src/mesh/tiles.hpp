#pragma once
// Block tiles of T x T particles over the finest grid: the unit of ownership,
// partitioning and migration (docs/design.md §3). A tile's identity depends only on
// the grid and T, never on the number of ranks. Header-only and MPI-free, so
// the physics can order its reductions by tile.
#include <algorithm>
#include <cstdint>
#include <vector>

namespace drape {

struct TileRange {
  int i0, i1, j0, j1;  // half-open particle ranges
};

struct Tiling {
  int ni = 0, nj = 0, t = 50;
  int nti = 0, ntj = 0;  // tiles along i and j

  Tiling() = default;
  Tiling(int ni_, int nj_, int t_)
      : ni(ni_), nj(nj_), t(t_), nti((ni_ + t_ - 1) / t_), ntj((nj_ + t_ - 1) / t_) {}

  int count() const { return nti * ntj; }
  int tile_of(int i, int j) const { return (i / t) * ntj + j / t; }
  int tile_of(int64_t p) const { return tile_of(int(p / nj), int(p % nj)); }
  TileRange range(int tile) const {
    const int ti = tile / ntj, tj = tile % ntj;
    return {ti * t, std::min(ni, (ti + 1) * t), tj * t, std::min(nj, (tj + 1) * t)};
  }
};

// Distinct owners (owner: rank per tile) of the particles in the clipped
// (2w+1)^2 window around (i, j), in order of first meeting. Tiles are
// rectangles: visiting the tiles the window overlaps suffices.
inline void window_owners(const Tiling& tl, const std::vector<int>& owner, int i, int j, int w,
                          std::vector<int>& out) {
  out.clear();
  const int i0 = std::max(0, i - w), i1 = std::min(tl.ni - 1, i + w);
  const int j0 = std::max(0, j - w), j1 = std::min(tl.nj - 1, j + w);
  for (int ti = i0 / tl.t; ti <= i1 / tl.t; ++ti)
    for (int tj = j0 / tl.t; tj <= j1 / tl.t; ++tj) {
      const int r = owner[ti * tl.ntj + tj];
      if (std::find(out.begin(), out.end(), r) == out.end()) out.push_back(r);
    }
}

}  // namespace drape
