#pragma once
// The AMRC hierarchy (docs/design.md §2): a quadtree of cells over the finest grid's
// (NI-1) x (NJ-1) intervals. A level-k cell spans 2^k intervals each way from
// an origin at multiples of 2^k, clipped at the far borders; level 0 is the
// finest. The leaves are the active mesh. They are stored as the level of the
// leaf over each finest interval, so refining and coarsening rewrite bytes in
// place and never allocate.
//
// Marks on the particles (ParticleFlag, Cloth::level):
//   active   a corner of some leaf;
//   hanging  active, but inside a side of a coarser leaf (the paper's "ghost
//            particle"): its position is interpolated from that side's ends;
//   level    the level of the finest leaf it is a corner of.
// Neighbouring leaves (sharing part of a side) differ by at most one level.
#include <cstdint>
#include <vector>

namespace drape {

struct Cell {
  int i = 0, j = 0;  // origin: particle indices, multiples of 2^level
  int level = 0;
  bool operator==(const Cell& o) const { return i == o.i && j == o.j && level == o.level; }
};

class Quadtree {
 public:
  Quadtree() = default;
  // Every leaf at level 0 (the run starts at the finest mesh).
  Quadtree(int ni, int nj, int max_level);
  // Copies the tree, not the scratch space (which the original reserved so
  // that adapting during a run does not allocate).
  Quadtree(const Quadtree& o) : ni_(o.ni_), nj_(o.nj_), max_level_(o.max_level_), level_(o.level_) {}
  Quadtree& operator=(const Quadtree& o) {
    ni_ = o.ni_;
    nj_ = o.nj_;
    max_level_ = o.max_level_;
    level_ = o.level_;  // same sizes during a run: no allocation
    return *this;
  }

  int ni() const { return ni_; }
  int nj() const { return nj_; }
  int max_level() const { return max_level_; }
  // The leaf level over every finest interval (checkpoints); set_levels
  // takes such an array back (it must describe a balanced tree).
  const std::vector<uint8_t>& levels() const { return level_; }
  // Calls f(leaf) for every leaf, row by row (no allocation).
  template <class F>
  void for_each_leaf(F&& f) const {
    for (int ci = 0; ci < ni_ - 1; ++ci)
      for (int cj = 0; cj < nj_ - 1; ++cj) {
        const Cell c = leaf_at(ci, cj);
        if (c.i == ci && c.j == cj) f(c);  // the leaf's first interval
      }
  }
  void set_levels(const std::vector<uint8_t>& levels);

  // The leaf over finest interval (ci, cj).
  Cell leaf_at(int ci, int cj) const;
  // The leaves, in order of their first finest interval (row by row).
  void leaves(std::vector<Cell>& out) const;
  // Particle index range of a cell: [i, i_end] x [j, j_end] (inclusive ends).
  int i_end(const Cell& c) const;
  int j_end(const Cell& c) const;

  // --- refine.cpp: split a leaf into its children, first refining the
  // neighbours that would otherwise be two levels coarser (2:1 balance).
  bool can_refine(const Cell& leaf) const { return leaf.level > 0; }
  void refine(const Cell& leaf);

  // --- coarsen.cpp: merge the children of `parent` (all leaves one level
  // finer) when no neighbour is finer than they are, so balance holds.
  bool can_coarsen(const Cell& parent) const;
  bool coarsen(const Cell& parent);  // false (and no change) where it cannot

  // 2:1 balance across every leaf side.
  bool balanced() const;

  // Writes flags (kActive, kHanging; other bits kept) and levels per particle.
  void mark(std::vector<uint8_t>& flags, std::vector<uint8_t>& level) const;

  // The ends of the coarse side a hanging particle lies on (particle ids);
  // false if p is not hanging. It lies in the middle, except on a side
  // clipped at the far border: weights follow the distance along the side.
  bool hanging_parents(int64_t p, int64_t& a, int64_t& b) const;

  // Mass per active particle: each leaf's area (clipped) times `density`,
  // a quarter to each corner; a hanging particle's share goes to the ends
  // of its coarse side by the interpolation weights (it is not solved for).
  // Inactive particles: 0. Held in slots (slot: the grid's slot map, -1
  // where not held, mass sized to the held particles; null: every particle
  // at its grid id): a held particle's share from one not held is left out,
  // which only ghosts beyond the ring can miss (a side's chain of hanging
  // particles spans under 2^(max level + 1) particles).
  void masses(double density, double hi, double hj, const int32_t* slot, std::vector<double>& mass) const;

  // Whether the grid-line segment between particles a < b lies on leaf
  // sides all along (an edge of the mesh may join them).
  bool on_side(int64_t a, int64_t b) const;

  struct Hanging {
    int64_t side, h, a, b;  // side length (particle ids apart), particle, ends
    double t;               // position along the side: x_h = (1 - t) x_a + t x_b
    bool operator<(const Hanging& o) const { return side != o.side ? side < o.side : h < o.h; }
  };
  // Every hanging particle, finest sides first (in the tree's scratch space).
  const std::vector<Hanging>& hanging() const;

  // Puts every hanging particle (3 values per particle in x) on its coarse
  // side, linearly between its ends, coarsest sides first (ends may hang).
  void interpolate_hanging(double* x) const;

 private:
  bool is_leaf(const Cell& c) const;
  void set_level(const Cell& c, int level);
  // The finest intervals along the cell's four sides, just outside it.
  template <class F>
  void each_outside_neighbour(const Cell& c, F&& f) const;
  bool on_grid(int ci, int cj) const { return ci >= 0 && cj >= 0 && ci < ni_ - 1 && cj < nj_ - 1; }
  int64_t id(int i, int j) const { return int64_t(i) * nj_ + j; }

  int ni_ = 0, nj_ = 0, max_level_ = 0;
  std::vector<uint8_t> level_;  // per finest interval (ci * (nj-1) + cj)
  mutable std::vector<Hanging> hang_;  // scratch for hanging()
};

template <class F>
inline void Quadtree::each_outside_neighbour(const Cell& c, F&& f) const {
  const int ie = i_end(c), je = j_end(c);
  for (int cj = c.j; cj < je; ++cj) {
    if (on_grid(c.i - 1, cj)) f(c.i - 1, cj);
    if (on_grid(ie, cj)) f(ie, cj);
  }
  for (int ci = c.i; ci < ie; ++ci) {
    if (on_grid(ci, c.j - 1)) f(ci, c.j - 1);
    if (on_grid(ci, je)) f(ci, je);
  }
}

}  // namespace drape
