// Self-contact with AMRC (docs/design.md §2): self-contact pushes apart
// free particles, so where two parts of the cloth approach, each must be on
// leaves fine enough that neither sheet can pass between the other's
// particles. The criterion keeps such regions at the finest level: a leaf
// splits while another part of the cloth lies within the distance from
// which it could reach the leaf's surface unseen.
//
// Every point of a leaf's surface lies within r(l) = 0.75 x (its rest
// diagonal) of one of its corners (half the diagonal on a flat square, with
// room for the strain of a leaf that is not bent: a bent one splits anyway).
// Two leaf surfaces within D of each other, at levels la >= lb, have
// corners within D + r(la) + r(lb) <= D + 2 r(la): the coarser leaf sees the
// other at one of its own particles and splits, down to the finest level.
// One more leaf width covers the motion until the next adaptation:
//   split_reach(l) = D + 2^l (1.5 diag + max(hi, hj)),
// and a cell forms only where nothing lies within keep_reach(l) = 1.5 x that
// (the gap keeps a leaf from flipping between adaptations). Particles of the
// same sheet that lie that close at rest do not count: a fold that brings
// them together turns the mesh lines, and the bending criterion splits it.
#include <algorithm>
#include <cmath>

#include "amrc/amrc.hpp"
#include "amrc/per_particle.hpp"

namespace drape {

namespace {

struct NearReach {
  double pair, diag, wide;
  double split(int l) const { return pair + std::ldexp(1.5 * diag + wide, l); }
  double keep(int l) const { return 1.5 * split(l); }
};

// The coarsest level of the leaves particle (i, j) is a corner or side of.
int coarsest_leaf(const Quadtree& t, int i, int j) {
  int top = 0;
  for (int ci = std::max(i - 1, 0); ci <= std::min(i, t.ni() - 2); ++ci)
    for (int cj = std::max(j - 1, 0); cj <= std::min(j, t.nj() - 2); ++cj) top = std::max(top, t.leaf_at(ci, cj).level);
  return top;
}

struct HashGrid {
  double cell;
  int64_t buckets;
  void cell_of(const double* x, int64_t c[3]) const {
    for (int k = 0; k < 3; ++k) c[k] = int64_t(std::floor(x[k] / cell));
  }
  int64_t bucket(int64_t cx, int64_t cy, int64_t cz) const {
    const uint64_t h = uint64_t(cx) * 73856093u ^ uint64_t(cy) * 19349663u ^ uint64_t(cz) * 83492791u;
    return int64_t(h & uint64_t(buckets - 1));
  }
};

}  // namespace

void Amrc::near_sheets(const Cloth& c, double pair_distance, const AdaptShare& share, std::vector<double>& out) {
  const Grid& g = c.grid;
  const int64_t n = g.n();
  const int top_level = tree_.max_level();
  const NearReach reach{pair_distance, std::hypot(g.hi, g.hj), std::max(g.hi, g.hj)};
  // The active particles in id order, and their positions from their owners
  // (every rank holds the same tree, so the same packing).
  int64_t m = 0;
  for (int64_t p = 0; p < n; ++p) {
    packed_at_[p] = c.active(p) ? int32_t(m) : -1;
    if (c.active(p)) packed_ids_[m++] = int32_t(p);
  }
  double* xs = packed_x_.data();
  const double* x = c.x();
  if (!share.tiling) {
    for (int64_t k = 0; k < m; ++k)
      for (int a = 0; a < 3; ++a) xs[3 * k + a] = x[3 * packed_ids_[k] + a];
  } else {
    std::fill(xs, xs + 3 * m, -HUGE_VAL);  // the owner's value wins the max
    for (int t : *share.tiles) {
      const TileRange r = share.tiling->range(t);
      for (int i = r.i0; i < r.i1; ++i)
        for (int j = r.j0; j < r.j1; ++j) {
          const int64_t k = packed_at_[g.id(i, j)];
          if (k >= 0)
            for (int a = 0; a < 3; ++a) xs[3 * k + a] = x[3 * g.id(i, j) + a];
        }
    }
    share.reducer->max_each(xs, 3 * m);
  }
  // Counting sort by bucket (serial: the same hash on any thread count).
  HashGrid hash{reach.keep(1), 1};
  while (hash.buckets < 2 * m) hash.buckets *= 2;
  int32_t* start = bucket_start_.data();
  std::fill(start, start + hash.buckets + 1, 0);
  int64_t cell[3];
  for (int64_t k = 0; k < m; ++k) {
    hash.cell_of(xs + 3 * k, cell);
    ++start[hash.bucket(cell[0], cell[1], cell[2]) + 1];
  }
  for (int64_t b = 1; b <= hash.buckets; ++b) start[b] += start[b - 1];
  for (int64_t k = 0; k < m; ++k) {
    hash.cell_of(xs + 3 * k, cell);
    bucket_items_[start[hash.bucket(cell[0], cell[1], cell[2])]++] = int32_t(k);
  }
  for (int64_t b = hash.buckets; b > 0; --b) start[b] = start[b - 1];
  start[0] = 0;
  // The mask is an OR over candidates: the same in any order.
  per_particle(c, share, out, [&](int64_t p) {
    const int64_t kp = packed_at_[p];
    if (kp < 0) return 0.0;
    const int ip = g.i_of(p), jp = g.j_of(p);
    const int levels = std::min(top_level, coarsest_leaf(tree_, ip, jp) + 1);
    if (levels == 0) return 0.0;
    const double* xp = xs + 3 * kp;
    int64_t home[3];
    hash.cell_of(xp, home);
    const int64_t span = int64_t(std::ceil(reach.keep(levels) / hash.cell));
    const double far2 = reach.keep(levels) * reach.keep(levels), same2 = reach.keep(1) * reach.keep(1);
    unsigned mask = 0;
    for (int64_t a = -span; a <= span; ++a)
      for (int64_t b = -span; b <= span; ++b)
        for (int64_t e = -span; e <= span; ++e) {
          const int64_t cx = home[0] + a, cy = home[1] + b, cz = home[2] + e;
          const int64_t bk = hash.bucket(cx, cy, cz);
          // A particle of another cell in this bucket needs no skipping: the
          // mask is an OR, and one outside the searched cells lies beyond far.
          for (int32_t s = start[bk]; s < start[bk + 1]; ++s) {
            const int64_t q = packed_ids_[bucket_items_[s]];
            const double di = (g.i_of(q) - ip) * g.hi, dj = (g.j_of(q) - jp) * g.hj;
            const double rest2 = di * di + dj * dj;
            if (rest2 <= same2) continue;  // the same sheet at every level's reach (p itself too)
            const double* xq = xs + 3 * int64_t(bucket_items_[s]);
            double d2 = 0;
            for (int k = 0; k < 3; ++k) d2 += (xq[k] - xp[k]) * (xq[k] - xp[k]);
            if (d2 >= far2) continue;
            for (int l = 1; l <= levels; ++l) {
              const double keep = reach.keep(l), split = reach.split(l);
              if (rest2 <= keep * keep) break;  // the same sheet at this level's reach, and so at coarser ones'
              if (d2 < split * split) mask |= 1u << l;
              if (d2 < keep * keep) mask |= 1u << (kKeepFine + l);
            }
          }
        }
    return double(mask);
  });
}

}  // namespace drape
