// The Newton solver's kernels: element forces set to their hysteresis targets
// and the stiffness K = dr/dx applied to a vector, matrix-free. Same passes
// and fixed-order gathers as the cost (deterministic for any thread count).
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "solver/cost.hpp"
#include "solver/kernels.hpp"
#include "solver/shear_cell.hpp"

namespace drape {

namespace {
using V = V3<double>;
inline V at(const double* z, int64_t p) { return load3<double>(z + 3 * p); }
inline V3<Dual> at(const double* z, const double* v, int64_t p) { return load3(z + 3 * p, v + 3 * p); }
inline void put(double* out, const V& v) {
  out[0] = v.x;
  out[1] = v.y;
  out[2] = v.z;
}
inline V value_of(const V3<Dual>& a) { return {a.x.v, a.y.v, a.z.v}; }
inline V deriv_of(const V3<Dual>& a) { return {a.x.d, a.y.d, a.z.d}; }

// Each element's generalized strain at positions x, as its band reads it:
// edge strain (edge_strain_at), triple curvature about the frozen axis (ids:
// previous, centre, next), shear angle (ids: the cell's corners).
inline double triple_curvature(const double* x, const int64_t ids[3], const double* axis, double rest) {
  V g[3];
  return bend_angle(at(x, ids[0]), at(x, ids[1]), at(x, ids[2]), load3<double>(axis), g) / rest;
}
inline double shear_strain(const double* x, const int64_t ids[4]) {
  const CellAt a = cell_at(ids, x);
  V g[4];
  return shear_cell(a.x, g);
}
}  // namespace

double Evaluator::edge_strain_at(const double* x, int64_t s, int64_t pos, const int32_t* slot) const {
  V g[2];
  return edge_length(at(x, slot_in(slot, s >> 1)), at(x, slot_in(slot, edge_far(pos))), g) / rest_e_[pos] - 1;
}
double Evaluator::triple_curvature_at(const double* x, int64_t s, int64_t pos, const int32_t* slot) const {
  int64_t ids[3];
  triple_ids(s, pos, ids);
  for (int64_t& id : ids) id = slot_in(slot, id);
  return triple_curvature(x, ids, &axis_t_[3 * pos], triple_rest(s, pos));
}
double Evaluator::shear_strain_at(const double* x, int64_t s, int64_t pos, const int32_t* slot) const {
  int64_t ids[4];
  cell_ids(s, pos, ids);
  for (int64_t& id : ids) id = slot_in(slot, id);
  return shear_strain(x, ids);
}

void Evaluator::hysteresis_forces(double* z) {
  list_rows();
  settled_ = false;
  halo_.exchange(z, Halo::kPositions);  // ring elements' forces are computed here too
  interpolate_hanging(z);
  const Cloth& c = c_;
  element_passes(
      [&](int64_t s, int64_t pos) {
        z[c.force_index(0, s)] = m_.stretch[s & 1].stop(anc_e_[pos], edge_strain_at(z, s, pos)).f;
      },
      [&](int64_t s, int64_t pos) {
        z[c.force_index(1, s)] = m_.bend[s & 1].stop(anc_t_[pos], triple_curvature_at(z, s, pos)).f;
      },
      [&](int64_t s, int64_t pos) {
        z[c.force_index(2, s)] = m_.shear.stop(anc_s_[pos], shear_strain_at(z, s, pos)).f;
      });
}

void Evaluator::hysteresis_anchors(const double* x1, const double* z, const int32_t* slot) {
  // Each element's step-start force f1 (z's force slots) folded into its
  // anchor; only the active elements and the ring's, the ones that read it.
  list_rows(false);
  if (axes_stale_) freeze_bend_axes(c_.x1.data(), c_.slots());  // the strains read the axes
  anchors_stale_ = false;
  settled_ = false;  // new anchors: the kept stops are not theirs
  const Cloth& c = c_;
  for_edges([&](int64_t s, int64_t pos) {
    const Band& b = m_.stretch[s & 1];
    const double f = z[c.force_index(0, s)];
    anc_e_[pos] = b.reversal() > 0 ? b.anchor(f, edge_strain_at(x1, s, pos, slot)) : f;
  });
  for_triples([&](int64_t s, int64_t pos) {
    const Band& b = m_.bend[s & 1];
    const double f = z[c.force_index(1, s)];
    anc_t_[pos] = b.reversal() > 0 ? b.anchor(f, triple_curvature_at(x1, s, pos, slot)) : f;
  });
  for_shears([&](int64_t s, int64_t pos) {
    const Band& b = m_.shear;
    const double f = z[c.force_index(2, s)];
    anc_s_[pos] = b.reversal() > 0 ? b.anchor(f, shear_strain_at(x1, s, pos, slot)) : f;
  });
}

// What stiffness_product needs of a particle: its contact force, the force's
// size (0 where it does not touch) and slope. Its mass term's coefficient,
// mass times Model::inertia_coeff, is computed where read.
void Evaluator::contact_terms(int64_t p, const double* z, double* kc) const {
  double slope = 0;
  const bool touching = contact_force(m_.contact, z + 3 * p, kc, nullptr, nullptr, &slope);
  kc[3] = touching ? std::sqrt(kc[0] * kc[0] + kc[1] * kc[1] + kc[2] * kc[2]) : 0.0;
  kc[4] = slope;
}

// Adds particle p's friction block times v_p to out (nothing without friction).
void Evaluator::add_friction_product(int64_t p, const double* z, const double* vp, double* out) const {
  double blk[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  if (!friction_block(m_.contact, z + 3 * p, c_.x1_at(p), blk)) return;
  for (int i = 0; i < 3; ++i) out[i] += blk[3 * i] * vp[0] + blk[3 * i + 1] * vp[1] + blk[3 * i + 2] * vp[2];
}

void Evaluator::stiffness_product_local(const double* z, double* v, double* kv) {
  hold_stiffness(true);
  list_rows();
  use_local();
  if (pairs_numbered_ != self_.builds()) number_pairs();  // a new pair list on the same numbering
  if (pairs_missing_ > 0) throw std::logic_error("Evaluator: a self-contact partner has no index in the own numbering");
  halo_.exchange_at(v, halo_send_.data(), halo_recv_.data());
  interpolate_hanging_local(v);  // K acts on P v: hanging entries follow their ends
  // What depends on z alone (triples' and cells' strain gradients and slope
  // factors, edges' frozen tensions and slopes): kept by the diagonal (from
  // settled_cost's pass in Newton's order), or by a first product after a
  // list change; the products read it back, bit for bit the same numbers.
  // Not keeping, every product computes it. Edges' directions and lengths
  // and the particles' contact terms every product computes.
  // Keeping, the frozen slopes live in the kept numbers only: a product
  // needs the diagonal's first (Newton's order).
  if (keep_ && !kg_ready_) throw std::logic_error("Evaluator::stiffness_product: needs stiffness_diagonal first");
  const bool fill = !keep_;
  auto edge = [&](const ItemRun& run) { edge_products(run, z, v); };
  // The grid ids (z's) only where the z-only numbers are computed: the
  // operand's reads go through the own numbering's tables.
  auto triple = [&](int64_t s, int64_t pos) {
    double mine[kKgTriple];
    double* kg = keep_ ? &kg_t_[kKgTriple * pos] : mine;
    if (fill) {
      V g[3];
      triple_gradients(s, pos, z, g);
      kept_bend(width_t_[pos] * k_slope_t_[pos] / triple_rest(s, pos), g, kg);
    }
    const int32_t* l = &lo_t_[3 * pos];
    const V vk[3] = {at(v, l[0]), at(v, l[1]), at(v, l[2])};
    if (narrow_) {  // the particles multiply it by their kept gradients
      buf_t_[pos] = kept_bend_stiffness(kg, vk);
      return;
    }
    V out[3];
    kept_bend_product(kg, vk, out);
    for (int k = 0; k < 3; ++k) put(&buf_t_[kTripleSlot * pos + 3 * k], out[k]);
  };
  auto shear = [&](int64_t s, int64_t pos) {
    double mine[kKgCell];
    double* kg = keep_ ? &kg_s_[kKgCell * pos] : mine;
    if (fill) {
      V g[4];
      cell_gradients(s, pos, z, g);
      kept_gradients(cell_area_at(s, pos) * k_slope_s_[pos], g, 4, kg);
    }
    const int32_t* l = &lo_s_[4 * pos];
    const V vk[4] = {at(v, l[0]), at(v, l[1]), at(v, l[2]), at(v, l[3])};
    if (narrow_) {
      buf_s_[pos] = kept_gradient_stiffness<4>(kg, vk);
      return;
    }
    V out[4];
    kept_gradient_product<4>(kg, vk, out);
    for (int k = 0; k < 4; ++k) put(&buf_s_[kShearSlot * pos + 3 * k], out[k]);
  };
  // A particle's contact force, its size and slope (size 0 where it does
  // not touch): computed from z in each product where the diagonal found
  // the particle touching (keeping), or everywhere; its mass kept by the
  // diagonal in list order (keeping) times Model::inertia_coeff.
  const double inertia = m_.inertia_coeff();
  auto particle = [&](int64_t p, int64_t pos) {
    const double mass = (keep_ ? mass_k_[pos] : c_.mass_at(p)) * inertia;
    const double* vp = v + 3 * pos;  // the free particles come first, in list order
    double out[3];
    for (int k = 0; k < 3; ++k) out[k] = mass * vp[k];
    if (!keep_ || touch_[pos]) {
      double fc[kKc];
      contact_terms(p, z, fc);
      const double fn = fc[3], slope = fc[4];
      if (fn > 0) {  // slope * n (n.v); n from the force direction
        const double nv = (fc[0] * vp[0] + fc[1] * vp[1] + fc[2] * vp[2]) / fn;
        for (int k = 0; k < 3; ++k) out[k] += slope * nv * fc[k] / fn;
      }
      add_friction_product(p, z, vp, out);
    }
    if (m_.self_contact)  // partners: free here, or contact ghosts (numbered with the others)
      self_.add_product_local(pos, p, z, vp, v, out);
    gather_vector(rows_[pos], out);
    for (int k = 0; k < 3; ++k) kv[3 * pos + k] = out[k];
  };
  elements_then_particles(edge, triple, shear, [] {}, particle);
  hanging_into_ends_local(kv, [&](int64_t h, int64_t lh, const GatherRow& row, double* out) {  // P^T K P: no mass at h
    double fc[kKc];
    contact_terms(h, z, fc);
    const double fn = fc[3], slope = fc[4];
    const double* vh = v + 3 * lh;
    const double nv = fn > 0 ? (fc[0] * vh[0] + fc[1] * vh[1] + fc[2] * vh[2]) / fn : 0.0;
    for (int k = 0; k < 3; ++k) out[k] = fn > 0 ? slope * nv * fc[k] / fn : 0.0;
    add_friction_product(h, z, vh, out);
    gather_vector(row, out);
  }, 1.0, 0.0);
  kg_ready_ = true;
}

void Evaluator::triple_gradients(int64_t s, int64_t pos, const double* z, V g[3]) const {
  int64_t ids[3];
  triple_ids(s, pos, ids);
  bend_gradient(at(z, ids[0]), at(z, ids[1]), at(z, ids[2]), load3<double>(&axis_t_[3 * pos]), g);
}

void Evaluator::cell_gradients(int64_t s, int64_t pos, const double* z, V g[4]) const {
  int64_t ids[4];
  cell_ids(s, pos, ids);
  const CellAt a = cell_at(ids, z);
  shear_cell<double, false>(a.x, g);
}

void Evaluator::element_gradients(int kind, int64_t pos, const double* z, V* computed, V* kept) const {
  const bool triple = kind == 1;
  const ActiveList& own = triple ? lists_.triples : lists_.shears;
  const ActiveList& ring = triple ? lists_.ring_triples : lists_.ring_shears;
  const int64_t s = pos < own.size() ? own.items[size_t(pos)] : ring.items[size_t(pos - own.size())];
  if (triple) {
    triple_gradients(s, pos, z, computed);
    for (int k = 0; k < 3; ++k) kept[k] = kept_bend_gradient(&kg_t_[size_t(kKgTriple) * pos], k);
  } else {
    cell_gradients(s, pos, z, computed);
    for (int k = 0; k < 4; ++k) kept[k] = kept_cell_gradient(&kg_s_[size_t(kKgCell) * pos], k);
  }
}

// An edge's direction and length come from z in every product, keeping or
// not: reading z's positions moves fewer bytes than keeping 4 numbers an
// edge, and its square root is the cost pass's (the same bits). Four edges
// in the lanes: one square root and three divisions for four.
void Evaluator::edge_products(const ItemRun& run, const double* z, const double* v) {
  auto ends_moves = [&](int64_t pos) { return at(v, lo_e_[2 * pos + 1]) - at(v, lo_e_[2 * pos]); };
  in_fours(
      run,
      [&](int64_t k) {
#if DRAPE_LANES
        const int64_t pos = run.base + k;
        V a[4], b[4], ed[4];
        double tension[4], slope[4];
        for (int l = 0; l < 4; ++l) {
          const EdgeStiffness ks = edge_frozen(pos + l);
          a[l] = at(z, run.items[k + l] >> 1);
          b[l] = at(z, edge_far(pos + l));
          ed[l] = ends_moves(pos + l);
          tension[l] = ks.tension;
          slope[l] = ks.slope_per_rest;
        }
        const V4 e = lanes4(b) - lanes4(a);
        const V4 out = edge_product(e, sqrt4(dot(e, e)), loadu4(tension), loadu4(slope), loadu4(&width_e_[pos]),
                                    lanes4(ed));
        for (int l = 0; l < 4; ++l) put(&buf_e_[kEdgeEntry * (pos + l)], lane(out, l));  // a's: its negative
#else
        for (int l = 0; l < 4; ++l) {
          const int64_t pos = run.base + k + l;
          put(&buf_e_[kEdgeEntry * pos], edge_product(edge_stiffness_at(run.items[k + l], pos, z), ends_moves(pos)));
        }
#endif
      },
      [&](int64_t k) {
        const int64_t pos = run.base + k;
        put(&buf_e_[kEdgeEntry * pos], edge_product(edge_stiffness_at(run.items[k], pos, z), ends_moves(pos)));
      });
}

void Evaluator::edge_numbers(int64_t s, int64_t pos, const double* z) {
  const int64_t p = s >> 1, q = edge_far(pos);
  V g[2];
  const double len = edge_length(at(z, p), at(z, q), g);
  const double L0 = rest_e_[pos];
  const Band::Stop st = m_.stretch[s & 1].stop(anc_e_[pos], len / L0 - 1);
  const double tension = std::max(0.0, st.f);
  if (keep_)
    edge_kept(tension, st.df_dq / L0, &kg_e_[kKgEdge * pos]);
  else
    k_tension_[pos] = tension, k_slope_e_[pos] = st.df_dq;
}

void Evaluator::triple_numbers(int64_t s, int64_t pos, const double* z, double* kg) {
  int64_t ids[3];
  triple_ids(s, pos, ids);
  V g[3];
  const double th =
      bend_angle(at(z, ids[0]), at(z, ids[1]), at(z, ids[2]), load3<double>(&axis_t_[3 * pos]), g);
  const double Lm = triple_rest(s, pos);
  const double slope = m_.bend[s & 1].stop(anc_t_[pos], th / Lm).df_dq;
  if (!keep_) k_slope_t_[pos] = slope;
  kept_bend(width_t_[pos] * slope / Lm, g, kg);
}

void Evaluator::shear_numbers(int64_t s, int64_t pos, const double* z, double* kg) {
  int64_t ids[4];
  cell_ids(s, pos, ids);
  const CellAt a = cell_at(ids, z);
  V g[4];
  const double phi = shear_cell(a.x, g);
  const double slope = m_.shear.stop(anc_s_[pos], phi).df_dq;
  if (!keep_) k_slope_s_[pos] = slope;
  kept_gradients(cell_area_at(s, pos) * slope, g, 4, kg);
}

// The diagonal of K: per element and particle, its stiffness block's
// diagonal, in the first entry of the particle's buffer entry, gathered.
// The elements' numbers are those settled_cost kept when it ran at this z
// (Newton's order: their strains, bands and angles are not computed a third
// time), else computed here; either way they stay kept (keep_products), so
// that a product computes only what is cheaper than reading it back (an
// edge's direction and length, a particle's contact).
void Evaluator::stiffness_diagonal_local(const double* z, double* diag) {
  hold_stiffness(true);
  list_rows();
  // At a z no evaluation saw (Newton's order never does that), a new pair
  // list's contact ghosts need their positions: z's ghost entries are a
  // copy of other ranks' values, refreshed as the other entry points do.
  if (refresh_pairs(z)) halo_.exchange(const_cast<double*>(z), Halo::kPositions);
  use_local();
  // A new pair list changes the halo's plan (its contact ghosts): the
  // numbering follows, before any product reads it.
  if (local_stale()) build_local(false);
  k_z_ = z;
  const bool settled = settled_;
  auto edge = [&](int64_t s, int64_t pos) {
    if (!settled) edge_numbers(s, pos, z);
    buf_e_[kEdgeEntry * pos] = edge_diagonal(edge_stiffness_at(s, pos, z));  // both ends'
  };
  auto gradients = [](const double* kg, double* buf, int n) {
    for (int k = 0; k < n; ++k) buf[3 * k] = kept_gradient_diagonal(kg, k);
  };
  auto triple = [&](int64_t s, int64_t pos) {
    double mine[kKgTriple];
    double* kg = keep_ ? &kg_t_[kKgTriple * pos] : mine;
    if (!settled) triple_numbers(s, pos, z, kg);
    if (narrow_) return;  // the particles read the kept numbers
    double d[3];
    kept_bend_diagonal(kg, d);
    for (int k = 0; k < 3; ++k) buf_t_[kTripleSlot * pos + 3 * k] = d[k];
  };
  auto shear = [&](int64_t s, int64_t pos) {
    double mine[kKgCell];
    double* kg = keep_ ? &kg_s_[kKgCell * pos] : mine;
    if (!settled) shear_numbers(s, pos, z, kg);
    if (!narrow_) gradients(kg, &buf_s_[kShearSlot * pos], 4);
  };
  const double inertia = m_.inertia_coeff();
  auto particle = [&](int64_t p, int64_t pos) {
    double kc[kKc];
    contact_terms(p, z, kc);
    bool held = false;
    const double friction = friction_trace(m_.contact, z + 3 * p, c_.x1_at(p), &held);
    const double mass = c_.mass_at(p);
    // The product adds a contact term where the force is non-zero, a
    // friction block where a surface holds the particle.
    if (keep_) {
      touch_[pos] = kc[3] > 0 || held;
      mass_k_[pos] = mass;
    }
    double dsum = mass * inertia + kc[4] / 3;
    if (m_.contact.has_friction()) dsum += friction / 3;
    if (m_.self_contact) dsum += self_.slope_sum(pos, p, z) / 3;
    gather_diagonal(rows_[pos], dsum);
    for (int k = 0; k < 3; ++k) diag[3 * pos + k] = dsum;
  };
  elements_then_particles(edge, triple, shear, [] {}, particle);
  hanging_into_ends_local(diag, [&](int64_t h, int64_t, const GatherRow& row, double* out) {
    double kc[kKc];
    contact_terms(h, z, kc);
    double dsum = kc[4] / 3;
    if (m_.contact.has_friction()) dsum += friction_trace(m_.contact, z + 3 * h, c_.x1_at(h)) / 3;
    gather_diagonal(row, dsum);
    out[0] = out[1] = out[2] = dsum;
  }, 2.0, 1.0);
  kg_ready_ = keep_;
}

// The grid-layout forms (tests, tools): v copied into the own numbering,
// the results back to the free and hanging particles' entries (and v's
// interpolated and received entries back to v).
void Evaluator::stiffness_product(const double* z, double* v, double* kv) {
  const LocalNumbering& ln = numbering();
  const int64_t n = ln.size(), listed = ln.free_count() + int64_t(lists_.hanging.size());
  std::vector<double> vl(3 * size_t(n)), kl(3 * size_t(n), 0.0);
  for (int64_t l = 0; l < n; ++l)
    for (int k = 0; k < 3; ++k) vl[3 * l + k] = v[3 * ln.id_of(l) + k];
  stiffness_product_local(z, vl.data(), kl.data());
  for (int64_t l = 0; l < n; ++l)
    for (int k = 0; k < 3; ++k) {
      v[3 * ln.id_of(l) + k] = vl[3 * l + k];
      if (l < listed) kv[3 * ln.id_of(l) + k] = kl[3 * l + k];
    }
}

void Evaluator::stiffness_diagonal(const double* z, double* diag) {
  const LocalNumbering& ln = numbering();
  const int64_t listed = ln.free_count() + int64_t(lists_.hanging.size());
  std::vector<double> dl(3 * size_t(ln.size()), 0.0);
  stiffness_diagonal_local(z, dl.data());
  for (int64_t l = 0; l < listed; ++l)
    for (int k = 0; k < 3; ++k) diag[3 * ln.id_of(l) + k] = dl[3 * l + k];
}

}  // namespace drape
