#include "amrc/amrc.hpp"

#include <algorithm>
#include <cmath>

#include "amrc/per_particle.hpp"
#include "amrc/remesh.hpp"

namespace drape {

namespace {

double turning_angle(const double* a, const double* b, const double* c) {
  double u[3], v[3];
  for (int k = 0; k < 3; ++k) {
    u[k] = b[k] - a[k];
    v[k] = c[k] - b[k];
  }
  const double cx = u[1] * v[2] - u[2] * v[1], cy = u[2] * v[0] - u[0] * v[2], cz = u[0] * v[1] - u[1] * v[0];
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), u[0] * v[0] + u[1] * v[1] + u[2] * v[2]);
}

// A cell's corners and particle (i, j)'s bilinear weights on them.
struct Corners {
  int64_t id[4];
  double w[4];
};

Corners corners_in(const Quadtree& t, const Cell& c, int i, int j) {
  const int ie = t.i_end(c), je = t.j_end(c);
  const double u = double(i - c.i) / (ie - c.i), v = double(j - c.j) / (je - c.j);
  const int64_t nj = t.nj();
  return {{c.i * nj + c.j, ie * nj + c.j, c.i * nj + je, ie * nj + je},
          {(1 - u) * (1 - v), u * (1 - v), (1 - u) * v, u * v}};
}

Corners corners_of(const Quadtree& t, int i, int j) {
  return corners_in(t, t.leaf_at(std::min(i, t.ni() - 2), std::min(j, t.nj() - 2)), i, j);
}

void place(const Corners& k, const double* x, double* y) {
  for (int a = 0; a < 3; ++a) {
    y[a] = 0;
    for (int q = 0; q < 4; ++q) y[a] += k.w[q] * x[3 * k.id[q] + a];
  }
}

}  // namespace

void Amrc::memory(MemoryTable& t) const {
  auto cap = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  t.add("Amrc", "trees' levels", cap(tree_.levels()) + cap(old_.levels()));
  t.add("Amrc", "criterion's bits (indicator and speed, inside, near)", cap(marks_) + cap(inside_) + cap(near_));
  t.add("Amrc", "near sheets' packed particles and tile boxes",
        cap(packed_ids_) + cap(packed_at_) + cap(packed_x_) + cap(tile_box_) + cap(tile_offset_));
  t.add("Amrc", "leaves (adapt's scratch)", cells_);
  t.add("Amrc", "the old mesh's marks",
        cap(was_active_) + cap(was_free_) + cap(edge_on_) + cap(triple_on_) + cap(shear_on_));
}

Amrc::Amrc(const Cloth& c, int max_level, bool near)
    : tree_(c.grid.ni, c.grid.nj, max_level), old_(tree_) {
  marks_.assign(c.grid.n(), 0);
  inside_.assign(c.grid.n(), 0);
  if (near) make_room_near(c);
  cells_.reserve(size_t(c.grid.ni - 1) * (c.grid.nj - 1));
  was_active_.assign(c.grid.n(), 0);
  was_free_.assign(c.grid.n(), 0);
  edge_on_ = c.edge_on;
  triple_on_ = c.triple_on;
  shear_on_ = c.shear_on;
}

void Amrc::make_room_near(const Cloth& c) {
  near_.assign(c.grid.n(), 0);
  packed_ids_.assign(c.grid.n(), 0);
  packed_at_.assign(c.grid.n(), -1);
  packed_x_.assign(3 * c.grid.n(), 0.0);
  // Tiles of 2^k x 2^k particles, k = 1 up to where at most 4 x 4 remain.
  tile_offset_.assign(2, 0);
  for (int k = 1;; ++k) {
    const int64_t di = (c.grid.ni + (1 << k) - 1) >> k, dj = (c.grid.nj + (1 << k) - 1) >> k;
    tile_offset_.push_back(tile_offset_.back() + di * dj);
    if (di <= 4 && dj <= 4) break;
  }
  tile_box_.assign(6 * tile_offset_.back(), 0.0);
}

void Amrc::criterion(const Cloth& c, const Thresholds& th, const AdaptShare& share, std::vector<uint32_t>& out) const {
  const double* x = c.x();
  const int top = tree_.max_level();
  per_particle(c, share, out, [&](int64_t p) {
    double m = 0;
    for (int d = 0; d < 2; ++d)
      if (c.triple_on_at(2 * p + d))
        m = std::max(m, turning_angle(x + 3 * c.prev_at(d, p), x + 3 * p, x + 3 * c.next_at(d, p)));
    // x1 - x2 is the step the next prediction extrapolates (time_loop.cpp).
    double speed = 0;
    if (th.coarsen_speed > 0 && c.active(p)) {
      const double *x1 = c.x1_at(p), *x2 = c.x2_at(p);
      double s = 0;
      for (int k = 0; k < 3; ++k) {
        const double dk = x1[k] - x2[k];
        s += dk * dk;
      }
      speed = std::sqrt(s) / c.dt_prev;
    }
    return criterion_bits(m, speed, th, top);
  });
}

void Amrc::inside(const Cloth& c, const Obstacle& ob, const AdaptShare& share, std::vector<uint32_t>& out) const {
  const double* x = c.x();
  const int top = tree_.max_level();
  per_particle(c, share, out, [&](int64_t p) {
    const int i = c.grid.i_of(p), j = c.grid.j_of(p);
    const int ci = std::min(i, c.grid.ni - 2), cj = std::min(j, c.grid.nj - 2);
    auto cuts = [&](const Corners& k) {
      double y[3];
      place(k, x, y);
      return clearance(ob, y) < -1e-9;  // a nanometre: a particle settled on a face may sit an ulp inside
    };
    unsigned mask = cuts(corners_of(tree_, i, j)) ? 1u : 0u;
    for (int l = 1; l <= top; ++l)
      if (cuts(corners_in(tree_, Cell{(ci >> l) << l, (cj >> l) << l, l}, i, j))) mask |= 1u << l;
    return mask;
  });
}

void Amrc::apply(Cloth& c, double density, bool shear) const { apply_tree(tree_, c, density, shear); }

void Amrc::lift_new_particles(Cloth& c, const Contact& contact) const {
  const Obstacle& ob = contact.obstacle;
  for (int64_t p = 0; p < c.grid.n(); ++p) {
    if (was_free_[p] || !c.free(p)) continue;
    double* x = c.x() + 3 * p;
    if (clearance(ob, x) >= contact.thickness) continue;
    double y[3] = {x[0], x[1], x[2]};
    push_out(ob, contact.thickness, y);
    const bool held = c.holds(p);  // the history of another rank's particle is its own
    for (int k = 0; k < 3; ++k) {
      const double d = y[k] - x[k];
      x[k] += d;
      if (!held) continue;
      c.x1_at(p)[k] += d;
      c.x2_at(p)[k] += d;
    }
  }
}

void Amrc::fill_inactive(Cloth& c) const {
  const int64_t n = c.grid.n();
  double* x = c.x();
#pragma omp parallel for schedule(static)
  for (int64_t p = 0; p < n; ++p) {
    if (c.active(p)) continue;
    double y[3];
    place(corners_of(tree_, c.grid.i_of(p), c.grid.j_of(p)), x, y);
    for (int a = 0; a < 3; ++a) x[3 * p + a] = y[a];
  }
}

AdaptStats Amrc::adapt(Cloth& c, double density, bool shear, const Thresholds& th, const AdaptShare& share,
                       const Obstacle* obstacle) {
  criterion(c, th, share, marks_);
  const bool solid = obstacle && obstacle->shape != ObstacleShape::None;
  if (solid) inside(c, *obstacle, share, inside_);
  old_ = tree_;
  const bool near = th.pair_distance > 0;
  if (near) near_sheets(c, th.pair_distance, share, near_);
  const AdaptStats st = drape::adapt(tree_, marks_, th, cells_, solid ? &inside_ : nullptr, near ? &near_ : nullptr);
  if (st.refined == 0 && st.coarsened == 0) return st;
  carry_over(c, density, shear);
  return st;
}

void Amrc::set_levels(Cloth& c, double density, bool shear, const std::vector<uint8_t>& levels) {
  old_ = tree_;
  tree_.set_levels(levels);
  carry_over(c, density, shear);
}

void Amrc::set_uniform_level(Cloth& c, double density, bool shear, int level) {
  set_levels(c, density, shear, std::vector<uint8_t>(tree_.levels().size(), uint8_t(level)));
}

// A new leaf's shear force (N/m, per unit width) is the area mean of the old
// leaves' over it: a split child keeps its parent's, a merged parent takes its
// children's mean. Each old leaf lies in one new leaf, so writing a new
// leaf's origin slot never changes what another new leaf reads.
// On several ranks only the cells whose origin this rank holds, from the
// old leaves it holds (as carry_position's history).
void Amrc::carry_shear(Cloth& c) const {
  tree_.for_each_leaf([&](const Cell& l) {
    const int64_t at = c.grid.id(l.i, l.j);
    if (!c.holds(at)) return;
    const int ie = tree_.i_end(l), je = tree_.j_end(l);
    double sum = 0;
    int count = 0;
    for (int ci = l.i; ci < ie; ++ci)
      for (int cj = l.j; cj < je; ++cj) {
        const Cell o = old_.leaf_at(ci, cj);
        const int64_t s = c.grid.id(o.i, o.j);
        if (!c.holds(s) || !shear_on_[size_t(c.slot(s))]) continue;
        sum += c.force(2, s);
        ++count;
      }
    c.force(2, at) = count > 0 ? sum / count : 0.0;
  });
}

namespace {
// A new particle's position and history on its old leaf. The history of a
// particle this rank does not hold is its owner's to carry; a corner it
// does not hold lies beyond its ghosts, so no particle whose history it
// holds for its own tiles or ring reads it (taken as 0 there).
void carry_position(Cloth& c, const Corners& k, int64_t p) {
  const bool held = c.holds(p);
  for (int a = 0; a < 3; ++a) {
    double x = 0, x1 = 0, x2 = 0;
    for (int q = 0; q < 4; ++q) {
      const int64_t id = k.id[q];
      x += k.w[q] * c.z[3 * id + a];
      if (!held || !c.holds(id)) continue;
      x1 += k.w[q] * c.x1_at(id)[a];
      x2 += k.w[q] * c.x2_at(id)[a];
    }
    c.z[3 * p + a] = x;
    if (!held) continue;
    c.x1_at(p)[a] = x1;
    c.x2_at(p)[a] = x2;
  }
}
}  // namespace

void Amrc::carry_over(Cloth& c, double density, bool shear) {
  const int64_t n = c.grid.n();
  for (int64_t p = 0; p < n; ++p) {
    was_active_[p] = c.active(p);
    was_free_[p] = c.free(p);
  }
  // Newly active particles: positions and history on the old leaf's surface;
  // the forces of the slots they start, from the old corners' slots that were
  // on (forces are per unit width, so a split edge keeps its tension).
  edge_on_ = c.edge_on;  // same sizes: copies without allocating
  triple_on_ = c.triple_on;
  shear_on_ = c.shear_on;
  carry_shear(c);
  apply(c, density, shear);
  for (int64_t p = 0; p < n; ++p) {
    if (was_active_[p] || !c.active(p)) continue;
    const Corners k = corners_of(old_, c.grid.i_of(p), c.grid.j_of(p));
    carry_position(c, k, p);
    if (!c.holds(p)) continue;  // its forces are its owner's to carry (held in slots)
    auto carry = [&](int b, const std::vector<uint8_t>& on) {
      for (int d = 0; d < 2; ++d) {
        double s = 0, w = 0;
        for (int q = 0; q < 4; ++q)
          if (c.holds(k.id[q]) && on[size_t(c.pair_slot(2 * k.id[q] + d))]) {
            s += k.w[q] * c.force(b, 2 * k.id[q] + d);
            w += k.w[q];
          }
        c.force(b, 2 * p + d) = w > 0 ? s / w : 0.0;
      }
    };
    carry(0, edge_on_);
    carry(1, triple_on_);
  }
}

}  // namespace drape
