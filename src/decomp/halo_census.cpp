#include "decomp/halo_census.hpp"

#include <algorithm>
#include <stdexcept>

namespace drape {

namespace {

// Whether a tile and its (up to 8) neighbours share one owner: then no
// window around its particles reaches another rank.
bool surrounded_by_own(const Tiling& tl, const std::vector<int>& owner, int t) {
  const int ti = t / tl.ntj, tj = t % tl.ntj;
  for (int di = -1; di <= 1; ++di)
    for (int dj = -1; dj <= 1; ++dj) {
      const int ui = ti + di, uj = tj + dj;
      if (ui < 0 || uj < 0 || ui >= tl.nti || uj >= tl.ntj) continue;
      if (owner[ui * tl.ntj + uj] != owner[t]) return false;
    }
  return true;
}

}  // namespace

HaloCensus halo_census(const Tiling& tl, const std::vector<int>& owner, int parts, int width) {
  if (width > tl.t) throw std::runtime_error("halo_census: width wider than a tile");
  HaloCensus h;
  h.sent.assign(parts, 0);
  h.received.assign(parts, 0);
  std::vector<std::vector<int>> peers(parts);  // sorted, unique after the loop
  std::vector<int> near, met;  // met: the ranks this tile's particles meet
  for (int t = 0; t < tl.count(); ++t) {
    if (surrounded_by_own(tl, owner, t)) continue;
    const TileRange r = tl.range(t);
    const int o = owner[t];
    met.clear();
    for (int i = r.i0; i < r.i1; ++i)
      for (int j = r.j0; j < r.j1; ++j) {
        window_owners(tl, owner, i, j, width, near);
        for (int q : near) {
          if (q == o) continue;
          ++h.sent[o];
          ++h.received[q];
          if (std::find(met.begin(), met.end(), q) == met.end()) met.push_back(q);
        }
      }
    for (int q : met) {
      peers[o].push_back(q);
      peers[q].push_back(o);
    }
  }
  h.neighbours.assign(parts, 0);
  for (int q = 0; q < parts; ++q) {
    std::sort(peers[q].begin(), peers[q].end());
    h.neighbours[q] = int(std::unique(peers[q].begin(), peers[q].end()) - peers[q].begin());
  }
  return h;
}

}  // namespace drape
