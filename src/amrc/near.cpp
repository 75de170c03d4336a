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
#include <stdexcept>

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

// A tile of the grid, 2^k x 2^k particles at pyramid level k, holds the
// bounding box of its active particles' positions (empty: lo > hi).
struct TileBox {
  const double* box;  // lo[3], hi[3]
  int i0, i1, j0, j1;  // the tile's grid range, clipped
};

// Lower bound on the squared distance from x to any point of the box, in
// the arithmetic of the pair test, so that it never exceeds a pair's d2.
double box_distance2(const double* box, const double* x) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double below = box[k] - x[k], above = x[k] - box[3 + k];
    const double d = below > 0 ? below : (above > 0 ? above : 0.0);
    d2 += d * d;
  }
  return d2;
}

// Upper bound on the squared rest distance from (ip, jp) to the tile.
double rest_reach2(const TileBox& t, int ip, int jp, double hi, double hj) {
  const double di = std::max(std::abs(t.i0 - ip), std::abs(t.i1 - 1 - ip)) * hi;
  const double dj = std::max(std::abs(t.j0 - jp), std::abs(t.j1 - 1 - jp)) * hj;
  return di * di + dj * dj;
}

// A tile may hold a counted pair only if, at some level l, part of it lies
// nearer than keep(l) in space while part of it lies farther than keep(l)
// at rest (the pair test counts d2 < keep(l)^2 < rest2 only).
bool may_count(double dmin2, double rmax2, const double* keep2, int levels) {
  for (int l = 1; l <= levels; ++l)
    if (dmin2 < keep2[l] && rmax2 > keep2[l]) return true;
  return false;
}

// The tiles' boxes, level 1 (2 x 2 particles) up to a top level of at most
// 4 x 4 tiles, each level's tiles row-major from offset[k].
struct Pyramid {
  double* box;
  const int64_t* offset;
  int levels, ni, nj;
  int dim_i(int k) const { return (ni + (1 << k) - 1) >> k; }
  int dim_j(int k) const { return (nj + (1 << k) - 1) >> k; }
  double* at(int k, int ti, int tj) const { return box + 6 * (offset[k] + int64_t(ti) * dim_j(k) + tj); }
  TileBox tile(int k, int ti, int tj) const {
    const int w = 1 << k;
    return {at(k, ti, tj), ti * w, std::min((ti + 1) * w, ni), tj * w, std::min((tj + 1) * w, nj)};
  }
  void build(const Grid& g, const int32_t* packed_at, const double* xs) const {
    for (int k = 1; k <= levels; ++k)
      for (int ti = 0; ti < dim_i(k); ++ti)
        for (int tj = 0; tj < dim_j(k); ++tj) {
          double* b = at(k, ti, tj);
          for (int a = 0; a < 3; ++a) b[a] = HUGE_VAL, b[3 + a] = -HUGE_VAL;
          if (k == 1) {
            const TileBox t = tile(1, ti, tj);
            for (int i = t.i0; i < t.i1; ++i)
              for (int j = t.j0; j < t.j1; ++j)
                if (packed_at[g.id(i, j)] >= 0) grow(b, xs + 3 * int64_t(packed_at[g.id(i, j)]));
          } else {
            for (int ci = 2 * ti; ci < std::min(2 * ti + 2, dim_i(k - 1)); ++ci)
              for (int cj = 2 * tj; cj < std::min(2 * tj + 2, dim_j(k - 1)); ++cj) merge(b, at(k - 1, ci, cj));
          }
        }
  }
  static void grow(double* b, const double* x) {
    for (int a = 0; a < 3; ++a) b[a] = std::min(b[a], x[a]), b[3 + a] = std::max(b[3 + a], x[a]);
  }
  static void merge(double* b, const double* c) {
    for (int a = 0; a < 3; ++a) b[a] = std::min(b[a], c[a]), b[3 + a] = std::max(b[3 + a], c[3 + a]);
  }
};

// Depth-first holds at most the top level's tiles and three siblings a level.
constexpr int kStackDepth = 16 + 3 * 32;

}  // namespace

void Amrc::near_sheets(const Cloth& c, double pair_distance, const AdaptShare& share, std::vector<uint32_t>& out) {
  const Grid& g = c.grid;
  const int64_t n = g.n();
  if (int64_t(packed_at_.size()) != n) throw std::logic_error("Amrc::near_sheets: built without `near` room");
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
  const Pyramid pyr{tile_box_.data(), tile_offset_.data(), int(tile_offset_.size()) - 2, g.ni, g.nj};
  pyr.build(g, packed_at_.data(), xs);
  double keep2[kKeepFine] = {0};
  for (int l = 1; l <= top_level; ++l) keep2[l] = reach.keep(l) * reach.keep(l);
  const double same2 = keep2[1];
  // The mask is an OR over candidates: the same in any order.
  per_particle(c, share, out, [&](int64_t p) {
    const int64_t kp = packed_at_[p];
    if (kp < 0) return 0u;
    const int ip = g.i_of(p), jp = g.j_of(p);
    const int levels = std::min(top_level, coarsest_leaf(tree_, ip, jp) + 1);
    if (levels == 0) return 0u;
    const double* xp = xs + 3 * kp;
    const double far2 = keep2[levels];
    unsigned mask = 0;
    auto pairs = [&](const TileBox& t) {
      for (int i = t.i0; i < t.i1; ++i)
        for (int j = t.j0; j < t.j1; ++j) {
          const int64_t q = g.id(i, j), kq = packed_at_[q];
          if (kq < 0) continue;
          const double di = (i - ip) * g.hi, dj = (j - jp) * g.hj;
          const double rest2 = di * di + dj * dj;
          if (rest2 <= same2) continue;  // the same sheet at every level's reach (p itself too)
          const double* xq = xs + 3 * kq;
          double d2 = 0;
          for (int k = 0; k < 3; ++k) d2 += (xq[k] - xp[k]) * (xq[k] - xp[k]);
          if (d2 >= far2) continue;
          for (int l = 1; l <= levels; ++l) {
            if (rest2 <= keep2[l]) break;  // the same sheet at this level's reach, and so at coarser ones'
            const double split = reach.split(l);
            if (d2 < split * split) mask |= 1u << l;
            if (d2 < keep2[l]) mask |= 1u << (kKeepFine + l);
          }
        }
    };
    // Depth first down the pyramid, past tiles that cannot hold a counted
    // pair: most of the own sheet lies either nearer than a level's reach
    // both at rest and now, or farther in both.
    struct Visit {
      int k, ti, tj;
    };
    Visit stack[kStackDepth];
    int top = 0;
    const int kt = pyr.levels;
    for (int ti = 0; ti < pyr.dim_i(kt); ++ti)
      for (int tj = 0; tj < pyr.dim_j(kt); ++tj) stack[top++] = {kt, ti, tj};
    while (top > 0) {
      const Visit v = stack[--top];
      const TileBox t = pyr.tile(v.k, v.ti, v.tj);
      if (!may_count(box_distance2(t.box, xp), rest_reach2(t, ip, jp, g.hi, g.hj), keep2, levels)) continue;
      if (v.k == 1) {
        pairs(t);
        continue;
      }
      for (int ci = 2 * v.ti; ci < std::min(2 * v.ti + 2, pyr.dim_i(v.k - 1)); ++ci)
        for (int cj = 2 * v.tj; cj < std::min(2 * v.tj + 2, pyr.dim_j(v.k - 1)); ++cj) stack[top++] = {v.k - 1, ci, cj};
    }
    return mask;
  });
}

}  // namespace drape
