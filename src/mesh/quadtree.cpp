// The quadtree's structure, its balance, and what it implies for particles:
// active and hanging marks, levels, masses. See quadtree.hpp.
#include "mesh/quadtree.hpp"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

#include "mesh/cloth.hpp"

namespace drape {

Quadtree::Quadtree(int ni, int nj, int max_level) : ni_(ni), nj_(nj), max_level_(max_level) {
  if (ni < 2 || nj < 2 || max_level < 0 || max_level > 12)
    throw std::invalid_argument("quadtree: grid needs 2 x 2 particles and 0 <= max_level <= 12");
  level_.assign(size_t(ni - 1) * (nj - 1), 0);
  hang_.reserve(size_t(ni) * nj);  // more than can hang
}

void Quadtree::set_levels(const std::vector<uint8_t>& levels) {
  if (levels.size() != level_.size()) throw std::invalid_argument("quadtree: levels of another grid");
  for (uint8_t l : levels)
    if (l > max_level_) throw std::invalid_argument("quadtree: a level above max_level");
  level_ = levels;
  for (int ci = 0; ci < ni_ - 1; ++ci)
    for (int cj = 0; cj < nj_ - 1; ++cj)
      if (!is_leaf(leaf_at(ci, cj))) throw std::invalid_argument("quadtree: levels that are not a tree");
  if (!balanced()) throw std::invalid_argument("quadtree: levels that are not 2:1 balanced");
}

Cell Quadtree::leaf_at(int ci, int cj) const {
  const int l = level_[size_t(ci) * (nj_ - 1) + cj];
  return {(ci >> l) << l, (cj >> l) << l, l};
}

int Quadtree::i_end(const Cell& c) const { return std::min(c.i + (1 << c.level), ni_ - 1); }
int Quadtree::j_end(const Cell& c) const { return std::min(c.j + (1 << c.level), nj_ - 1); }

void Quadtree::leaves(std::vector<Cell>& out) const {
  out.clear();
  for_each_leaf([&](const Cell& c) { out.push_back(c); });
}

bool Quadtree::is_leaf(const Cell& c) const {
  if (!on_grid(c.i, c.j)) return false;
  for (int ci = c.i; ci < i_end(c); ++ci)
    for (int cj = c.j; cj < j_end(c); ++cj)
      if (level_[size_t(ci) * (nj_ - 1) + cj] != c.level) return false;
  return true;
}

void Quadtree::set_level(const Cell& c, int level) {
  for (int ci = c.i; ci < i_end(c); ++ci)
    for (int cj = c.j; cj < j_end(c); ++cj) level_[size_t(ci) * (nj_ - 1) + cj] = uint8_t(level);
}

bool Quadtree::on_side(int64_t a, int64_t b) const {
  const int ia = int(a / nj_), ja = int(a % nj_), ib = int(b / nj_), jb = int(b % nj_);
  if (ia == ib) {  // along j on grid line i: a side of the leaves above it (or the border)
    for (int cj = ja; cj < jb; ++cj)
      if (ia < ni_ - 1 && leaf_at(ia, cj).i != ia) return false;
    return true;
  }
  for (int ci = ia; ci < ib; ++ci)  // along i on grid line j
    if (ja < nj_ - 1 && leaf_at(ci, ja).j != ja) return false;
  return true;
}

bool Quadtree::balanced() const {
  for (int ci = 0; ci < ni_ - 1; ++ci)
    for (int cj = 0; cj < nj_ - 1; ++cj) {
      const int l = level_[size_t(ci) * (nj_ - 1) + cj];
      if (on_grid(ci + 1, cj) && std::abs(l - level_[size_t(ci + 1) * (nj_ - 1) + cj]) > 1) return false;
      if (on_grid(ci, cj + 1) && std::abs(l - level_[size_t(ci) * (nj_ - 1) + cj + 1]) > 1) return false;
    }
  return true;
}

bool Quadtree::hanging_parents(int64_t p, int64_t& a, int64_t& b) const {
  const int i = int(p / nj_), j = int(p % nj_);
  bool corner = false, inside = false;
  for (int ci = i - 1; ci <= i; ++ci)
    for (int cj = j - 1; cj <= j; ++cj) {
      if (!on_grid(ci, cj)) continue;
      const Cell c = leaf_at(ci, cj);
      const int ie = i_end(c), je = j_end(c);
      const bool on_i = i == c.i || i == ie, on_j = j == c.j || j == je;
      if (on_i && on_j) {
        corner = true;
      } else if (on_i) {  // inside the side at fixed i
        inside = true;
        a = id(i, c.j);
        b = id(i, je);
      } else if (on_j) {  // inside the side at fixed j
        inside = true;
        a = id(c.i, j);
        b = id(ie, j);
      }
    }
  return corner && inside;
}

void Quadtree::mark(std::vector<uint8_t>& flags, std::vector<uint8_t>& level) const {
  const int64_t n = int64_t(ni_) * nj_;
  flags.resize(n);
  level.assign(n, 255);
  for (int64_t p = 0; p < n; ++p) flags[p] &= uint8_t(~(kActive | kHanging));
  for_each_leaf([&](const Cell& c) {
    const int ie = i_end(c), je = j_end(c);
    for (int i = c.i; i <= ie; ++i)
      for (int j = c.j; j <= je; ++j) level[id(i, j)] = std::min<uint8_t>(level[id(i, j)], uint8_t(c.level));
    for (int64_t q : {id(c.i, c.j), id(ie, c.j), id(c.i, je), id(ie, je)}) flags[q] |= kActive;
  });
  int64_t a, b;
  for (int64_t p = 0; p < n; ++p)
    if ((flags[p] & kActive) && hanging_parents(p, a, b)) flags[p] |= kHanging;
}

void Quadtree::masses(double density, double hi, double hj, const int32_t* slot, std::vector<double>& mass) const {
  if (slot)
    std::fill(mass.begin(), mass.end(), 0.0);  // sized by hold_particles: no allocation while stepping
  else
    mass.assign(size_t(ni_) * nj_, 0.0);
  auto at = [&](int64_t p) -> double* { return slot ? (slot[p] >= 0 ? &mass[size_t(slot[p])] : nullptr) : &mass[p]; };
  for_each_leaf([&](const Cell& c) {
    const int ie = i_end(c), je = j_end(c);
    const double quarter = 0.25 * density * (ie - c.i) * hi * (je - c.j) * hj;
    for (int64_t q : {id(c.i, c.j), id(ie, c.j), id(c.i, je), id(ie, je)})
      if (double* m = at(q)) *m += quarter;
  });
  // Hanging particles pass their mass to their side's ends, finest sides
  // first, so that mass reaching a hanging end moves on up.
  for (const Hanging& g : hanging()) {
    double* h = at(g.h);
    if (!h) continue;
    if (double* a = at(g.a)) *a += (1 - g.t) * *h;
    if (double* b = at(g.b)) *b += g.t * *h;
    *h = 0;
  }
}

const std::vector<Quadtree::Hanging>& Quadtree::hanging() const {
  hang_.clear();
  int64_t a, b;
  for (int64_t p = 0; p < int64_t(ni_) * nj_; ++p)
    if (hanging_parents(p, a, b)) hang_.push_back({std::abs(b - a), p, a, b, double(p - a) / double(b - a)});
  std::sort(hang_.begin(), hang_.end());
  return hang_;
}

void Quadtree::interpolate_hanging(double* x) const {
  const std::vector<Hanging>& hang = hanging();
  for (auto g = hang.rbegin(); g != hang.rend(); ++g)
    for (int k = 0; k < 3; ++k) x[3 * g->h + k] = (1 - g->t) * x[3 * g->a + k] + g->t * x[3 * g->b + k];
}

}  // namespace drape
