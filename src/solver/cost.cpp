#include "solver/cost.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <initializer_list>
#include <stdexcept>

#include "solver/elements/band_K.hpp"
#include "solver/fit.hpp"
#include "solver/kernels.hpp"
#include "solver/shear_cell.hpp"
#include "mesh/topology.hpp"

namespace drape {

namespace {
using V = V3<double>;
inline V at(const double* z, int64_t p) { return load3<double>(z + 3 * p); }
inline void put(double* out, const V& v, double s) {
  out[0] = s * v.x;
  out[1] = s * v.y;
  out[2] = s * v.z;
}

#if DRAPE_LANES
// Four elements' band and memory costs and their slopes (at cost, gq, gf:
// four consecutive list positions; gq null where no gradient is held), lane
// by lane the scalar passes' arithmetic: lam the cost's scale, gq divided
// by *div where theirs is (edges, triples).
void band_costs4(const BandFour& b, const StopFour& st, D4 f, D4 lam, bool use, double memory, const D4* div,
                 double* cost, double* gq, double* gf) {
  const D4 zero = splat4(0.0), mu = splat4(memory);
  const ExcessFour ex = use ? band_excess4(f, b) : ExcessFour{zero, zero};
  const D4 sigma = ex.r * lam, mem = (f - st.f) * lam;
  storeu4(cost, splat4(0.5) * (sigma * sigma + mu * mem * mem));
  if (!gq) return;
  const D4 slope = (sigma * ex.dr_dq - mu * mem * st.df_dq) * lam;
  storeu4(gq, div ? slope / *div : slope);
  storeu4(gf, (sigma + mu * mem) * lam);
}

// Four edges' stretch bands at their strains q (edge l's band by its
// direction, s[l] & 1): both directions' power laws in the lanes, any other
// band (measured curves) by Band::at lane by lane.
BandFour stretch_four(const Band stretch[2], const int64_t s[4], D4 q) {
  const Band* b[2] = {&stretch[0], &stretch[1]};
  if (b[0]->power_law() && b[1]->power_law()) {
    const Band::PowerLaw law[2] = {b[0]->power_law_terms(), b[1]->power_law_terms()};
    const Band::PowerLaw* p[4] = {&law[s[0] & 1], &law[s[1] & 1], &law[s[2] & 1], &law[s[3] & 1]};
    return tensile_band4(q, p);
  }
  BandValue bv[4];
  for (int l = 0; l < 4; ++l) bv[l] = b[s[l] & 1]->at(q[l]);
  return band_four(bv);
}

// Four elements' bands at their strains q (element l's: warp's where s[l]
// is even, else weft's): linear bands in the lanes, any other by Band::at
// lane by lane.
BandFour bands_four(const Band& warp, const Band& weft, const int64_t s[4], D4 q) {
  const Band* b[4] = {s[0] & 1 ? &weft : &warp, s[1] & 1 ? &weft : &warp, s[2] & 1 ? &weft : &warp,
                      s[3] & 1 ? &weft : &warp};
  if (warp.plain_linear() && weft.plain_linear())
    return linear_band4(q, D4{b[0]->slope(), b[1]->slope(), b[2]->slope(), b[3]->slope()},
                        D4{b[0]->half_width(), b[1]->half_width(), b[2]->half_width(), b[3]->half_width()});
  BandValue bv[4];
  for (int l = 0; l < 4; ++l) bv[l] = b[l]->at(q[l]);
  return band_four(bv);
}

BandValue lane_value(const BandFour& b, int l) { return {b.lo[l], b.hi[l], b.dlo[l], b.dhi[l]}; }
#endif
}  // namespace

Evaluator::Evaluator(const Cloth& cloth, const Model& model, const ActiveLists& lists,
                     const Tiling& tiling, const LoopPolicy& policy, const Reducer& reducer,
                     const Halo& halo)
    : c_(cloth), m_(model), lists_(lists), tiling_(tiling), pol_(policy), red_(reducer), halo_(halo) {
  if (cloth.grid.n() > kMaxParticles) throw std::length_error("Evaluator: more particles than GatherRow's offsets reach");
  keep_ = true;  // keep_products(true), sized below
  fit_arrays(true);
  partials_.assign(4 * size_t(tiling.count()), 0.0);
}


// Sizes per element: the owned elements and the ring's; per row: the free
// particles and the hanging ones.
void Evaluator::fit_arrays(bool exact) {
  const size_t n = size_t(c_.grid.n());
  const size_t ne = size_t(lists_.edges.size() + lists_.ring_edges.size());
  const size_t nt = size_t(lists_.triples.size() + lists_.ring_triples.size());
  const size_t ns = size_t(lists_.shears.size() + lists_.ring_shears.size());
  const size_t np = size_t(lists_.particles.size()), nr = np + lists_.hanging.size();
  // An array of `per` entries an element, of `count` elements, at most `most`.
  auto each = [exact](auto& v, size_t count, size_t per, size_t most, auto fill) {
    fit(v, per * count, per * most, exact, fill);
  };
  const size_t me = 2 * n, mt = 2 * n, ms = n;  // the grid's slots
  each(buf_e_, ne, kEdgeEntry, me, 0.0);
  narrow_ = keep_ && !wide_;
  each(buf_t_, nt, narrow_ ? 1 : kTripleSlot, mt, 0.0);
  each(buf_s_, ns, narrow_ ? 1 : kShearSlot, ms, 0.0);
  each(cost_e_, ne, 1, me, 0.0);
  each(cost_t_, nt, 1, mt, 0.0);
  each(cost_s_, ns, 1, ms, 0.0);
  if (slopes_) fit_slopes(exact);
  if (!stiffness_) {  // a nonlinear CG run's: no stiffness numbers at all
    for (auto* a : {&kg_e_, &kg_t_, &kg_s_, &k_tension_, &k_slope_e_, &k_slope_t_, &k_slope_s_})
      std::vector<double>().swap(*a);
  } else if (!keep_) {  // keeping, the kept numbers carry them
    each(k_tension_, ne, 1, me, 0.0);
    each(k_slope_e_, ne, 1, me, 0.0);
    each(k_slope_t_, nt, 1, mt, 0.0);
    each(k_slope_s_, ns, 1, ms, 0.0);
  } else {
    each(kg_e_, ne, kKgEdge, me, 0.0);
    each(kg_t_, nt, kKgTriple, mt, 0.0);
    each(kg_s_, ns, kKgCell, ms, 0.0);
    for (auto* a : {&k_tension_, &k_slope_e_, &k_slope_t_, &k_slope_s_}) std::vector<double>().swap(*a);
  }
  if (stiffness_ && keep_) {
    each(touch_, np, 1, n, uint8_t(0));
    each(mass_k_, np, 1, n, 0.0);
  } else {
    std::vector<uint8_t>().swap(touch_);
    std::vector<double>().swap(mass_k_);
  }
  each(rows_, nr, 1, n, GatherRow{});
  each(rho_, np, 3, n, 0.0);
  each(cost_p_, np, 1, n, 0.0);
  each(nb_e_, ne, 1, me, int32_t(-1));
  if (local_on_) {  // the triples' and cells' local indices name their neighbours
    fit_local_tables(exact);
  } else {
    each(nb_t_, nt, 2, mt, int32_t(-1));
    each(nb_s_, ns, 3, ms, int32_t(-1));
  }
  // Self-contact's arrays from its first build on (none before: a mesh that
  // is never stepped holds none).
  if (m_.self_contact && self_.builds() > 0) self_.fit_to_lists(lists_.particles, int64_t(n), exact);
  // Axes and anchors last from one step's start to the next: kept while the
  // lists stay (a new capacity for the same lists: keep_products).
  fit_keeping(axis_t_, 3 * nt, 3 * mt, exact, 0.0);
  fit_keeping(anc_e_, ne, me, exact, 0.0);
  fit_keeping(anc_t_, nt, mt, exact, 0.0);
  fit_keeping(anc_s_, ns, ms, exact, 0.0);
  // The rest geometry too (its edges' eased rest lengths are state).
  for (auto* v : {&rest_e_, &width_e_}) fit_keeping(*v, ne, me, exact, 0.0);
  fit_keeping(width_t_, nt, mt, exact, 0.0);
  active_.fit(0, ne, me, exact);
  active_.fit(1, nt, mt, exact);
  active_.fit(2, ns, ms, exact);
}

void Evaluator::fit_local_tables(bool exact) {
  const size_t n = size_t(c_.grid.n());
  fit(lo_e_, 2 * size_t(lists_.edges.size() + lists_.ring_edges.size()), 4 * n, exact, int32_t(-1));
  fit(lo_t_, 3 * size_t(lists_.triples.size() + lists_.ring_triples.size()), 6 * n, exact, int32_t(-1));
  fit(lo_s_, 4 * size_t(lists_.shears.size() + lists_.ring_shears.size()), 4 * n, exact, int32_t(-1));
}

void Evaluator::fit_to_lists(bool exact) {
  fit_arrays(exact);
  kg_ready_ = settled_ = false;  // the kept numbers may be gone
  rows_stamp_ = 0;               // and the rows
  if (local_on_) build_local(exact);  // between steps: a solver sizes its local vectors by it
}

void Evaluator::keep_products(bool on) {
  for (auto* a : {&kg_e_, &kg_t_, &kg_s_}) std::vector<double>().swap(*a);  // off: no memory
  keep_wanted_ = on;
  keep_ = on && stiffness_;
  fit_to_lists(true);  // the frozen slopes' arrays follow (off: held); may move the rows: listed again at the next call
  kg_ready_ = settled_ = false;
}

void Evaluator::widen() {
  if (wide_) return;
  wide_ = true;
  fit_arrays(false);  // the buffers grow to their wide entries; their contents are rewritten before read
}

void Evaluator::hold_stiffness(bool on) {
  if (on == stiffness_) return;
  stiffness_ = on;
  keep_ = keep_wanted_ && on;
  fit_arrays(true);  // frees them (off) or sizes them to the lists (on), the buffers to their widths
  kg_ready_ = settled_ = false;
}

void Evaluator::memory(MemoryTable& t) const {
  const char* o = "Evaluator";
  auto sum = [](std::initializer_list<const std::vector<double>*> vs) {
    size_t b = 0;
    for (const auto* v : vs) b += v->capacity() * sizeof(double);
    return b;
  };
  t.add(o, "element buffers (edges, triples, cells)", sum({&buf_e_, &buf_t_, &buf_s_}));
  t.add(o, "products' kept numbers (elements)", sum({&kg_e_, &kg_t_, &kg_s_}));
  t.add(o, "products' kept touches and masses (particles)",
        touch_.capacity() * sizeof(uint8_t) + mass_k_.capacity() * sizeof(double));
  t.add(o, "particles' Newton costs", cost_p_);
  t.add(o, "band costs, slopes, force derivatives",
        sum({&cost_e_, &cost_t_, &cost_s_, &gq_e_, &gq_t_, &gq_s_, &gf_e_, &gf_t_, &gf_s_}));
  t.add(o, "residual", rho_);
  t.add(o, "residual at z's positions (gradients only)", rho_grid_);
  t.add(o, "K's frozen slopes and tensions", sum({&k_slope_e_, &k_slope_t_, &k_slope_s_, &k_tension_}));
  t.add(o, "gather rows", rows_);
  t.add(o, "neighbours in list order", (nb_e_.capacity() + nb_t_.capacity() + nb_s_.capacity()) * sizeof(int32_t));
  t.add(o, "elements' particles in the own numbering",
        (lo_e_.capacity() + lo_t_.capacity() + lo_s_.capacity()) * sizeof(int32_t));
  t.add(o, "own numbering (hanging, others; their halo and hanging indices)",
        local_.bytes() + (hang_lo_.capacity() + halo_send_.capacity() + halo_recv_.capacity()) * sizeof(int32_t));
  t.add(o, "hanging particles' results (own numbering)", hpend_lo_);
  t.add(o, "bending axes", axis_t_);
  t.add(o, "rest geometry (lengths, widths)", sum({&rest_e_, &width_e_, &width_t_}));
  t.add(o, "band anchors (step-start forces)", sum({&anc_e_, &anc_t_, &anc_s_}));
  if (active_.enabled()) t.add(o, "band branches at z and a trial (kinks' active set)", active_.bytes());
  t.add(o, "hanging particles' forces and results",
        sum({&hres_, &hpend_}) + (hslot_.capacity() + row_hslot_.capacity()) * sizeof(int32_t) +
            hsort_.capacity() * sizeof(hsort_[0]));
  t.add(o, "assembly maps",
        (asm_index_.capacity() + asm_hang_.capacity()) * sizeof(int32_t) +
            (hx_start_.capacity() + ht_start_.capacity()) * sizeof(int64_t) +
            (hx_.capacity() + ht_.capacity()) * sizeof(HxEntry));
  t.add(o, "numeric gradient's copy of z", zwork_);
  self_.memory(t);
}

// ---- the element buffers in list order -----------------------------------

// The lists hold their slots in ascending order within each owned tile
// (lists_.tiles ascending) and along the ring: a binary search finds one
// slot (a row's slots: ListWalk), where a map by slot would be sized by the
// grid on every rank.
int64_t Evaluator::particle_entry(int64_t p) const {
  if (!compact_) return 3 * p;
  const int64_t pos = list_position(p);
  return pos >= 0 ? 3 * pos : -1;
}

int64_t Evaluator::list_position(int64_t p) const {
  const std::vector<int>& tiles = lists_.tiles;
  const auto k = std::lower_bound(tiles.begin(), tiles.end(), tiling_.tile_of(p));
  if (k == tiles.end() || *k != tiling_.tile_of(p)) return -1;
  const ActiveList& pl = lists_.particles;
  const size_t kt = size_t(k - tiles.begin());
  const int64_t *b = pl.items.data() + pl.tile_begin[kt], *e = pl.items.data() + pl.tile_begin[kt + 1];
  const int64_t* f = std::lower_bound(b, e, p);
  return f != e && *f == p ? f - pl.items.data() : -1;
}

int64_t Evaluator::position_of(int kind, int64_t s) const {
  const ActiveList* own[3] = {&lists_.edges, &lists_.triples, &lists_.shears};
  const ActiveList* ring[3] = {&lists_.ring_edges, &lists_.ring_triples, &lists_.ring_shears};
  const ActiveList& o = *own[kind];
  auto find = [s](const int64_t* b, const int64_t* e) {
    const int64_t* f = std::lower_bound(b, e, s);
    return f != e && *f == s ? f : nullptr;
  };
  const std::vector<int>& tiles = lists_.tiles;
  const int t = tiling_.tile_of(kind == 2 ? s : s >> 1);
  const auto k = std::lower_bound(tiles.begin(), tiles.end(), t);
  if (k != tiles.end() && *k == t) {  // this rank's tile: its list, or none
    const size_t kt = size_t(k - tiles.begin());
    const int64_t* f = find(o.items.data() + o.tile_begin[kt], o.items.data() + o.tile_begin[kt + 1]);
    return f ? f - o.items.data() : -1;
  }
  const ActiveList& r = *ring[kind];
  const int64_t* f = find(r.items.data(), r.items.data() + r.size());
  return f ? o.size() + (f - r.items.data()) : -1;
}

bool Evaluator::listed_row(int64_t p, GatherRow& row) const {
  ListWalk walk(lists_, tiling_);
  return listed_row(p, row, walk);
}

bool Evaluator::listed_row(int64_t p, GatherRow& row, ListWalk& walk) const {
  std::fill(row.at, row.at + 16, -1);
  bool listed = true;
  for_gathered(p, [&](int place, int kind, int64_t s, int) {
    const int64_t pos = walk.position(place, kind, s);
    // An edge's one entry serves both its ends (the gather knows which by
    // place); a triple's or cell's position (its part too is the place's).
    if (pos >= 0)
      row.at[place] = int32_t(kind == 0 ? kEdgeEntry * pos : pos);
    else
      listed = false;
  });
  return listed;
}

void Evaluator::list_rows(bool derive) {
  build_rows();
  lay_out_rest();
  if (local_on_ && local_stale()) build_local(false);
  // New lists: the axes and anchors held are in the old lists' order. An
  // entry point that reads them first computes them from the cloth's history
  // and forces (the step's start computes both itself, with the ghosts
  // current, before any other: no work twice).
  if (derived_stamp_ != lists_.stamp) {
    axes_stale_ = anchors_stale_ = true;
    derived_stamp_ = lists_.stamp;
  }
  if (derive && axes_stale_) freeze_bend_axes(c_.x1.data(), c_.slots());
  if (derive && anchors_stale_) hysteresis_anchors(c_.x1.data(), c_.z.data(), c_.slots());
}

void Evaluator::build_rows() {
  if (rows_stamp_ == lists_.stamp && lists_.stamp != 0 && rows_hanging_ == lists_.hanging.size()) return;
  rows_stamp_ = lists_.stamp;
  rows_hanging_ = lists_.hanging.size();
  fit_arrays(false);  // the lists' sizes, within the capacity unless they outgrew it
  number_hanging_slots();
  kg_ready_ = settled_ = false;  // kept in the old lists' order
  if (!std::is_sorted(lists_.tiles.begin(), lists_.tiles.end()))
    throw std::logic_error("Evaluator: the lists' tiles are not in ascending order");
  for (const ActiveList* r : {&lists_.ring_edges, &lists_.ring_triples, &lists_.ring_shears})
    if (!std::is_sorted(r->items.begin(), r->items.end()))
      throw std::logic_error("Evaluator: the ring's slots are not in ascending order");
  place_neighbours();
  const ActiveList& pl = lists_.particles;
  // Each thread walks the lists beside its run of the particle list.
  int unlisted = 0;
#pragma omp parallel reduction(+ : unlisted)
  {
    ListWalk walk(lists_, tiling_);
#pragma omp for schedule(static)
    for (int64_t k = 0; k < pl.size(); ++k) unlisted += !listed_row(pl.items[k], rows_[k], walk);
  }
  if (unlisted > 0) throw std::logic_error("Evaluator: an owned particle's element is in no active list");
  ListWalk walk(lists_, tiling_);
  for (size_t i = 0; i < lists_.hanging.size(); ++i) listed_row(lists_.hanging[i].h, rows_[pl.size() + i], walk);
}

// Each element's neighbours, at its position (the ring's after the owned).
void Evaluator::place_neighbours() {
  auto place = [](const ActiveList& own, const ActiveList& ring, auto&& ends) {
    for (int64_t k = 0; k < own.size(); ++k) ends(own.items[k], k);
    for (int64_t k = 0; k < ring.size(); ++k) ends(ring.items[k], own.size() + k);
  };
  place(lists_.edges, lists_.ring_edges,
        [&](int64_t s, int64_t pos) { nb_e_[pos] = int32_t(c_.next_at(s & 1, s >> 1)); });
  if (local_on_) return;  // build_local, next in list_rows, numbers the triples' and cells'
  place(lists_.triples, lists_.ring_triples, [&](int64_t s, int64_t pos) {
    nb_t_[2 * pos] = int32_t(c_.prev_at(s & 1, s >> 1));
    nb_t_[2 * pos + 1] = int32_t(c_.next_at(s & 1, s >> 1));
  });
  place(lists_.shears, lists_.ring_shears, [&](int64_t s, int64_t pos) {
    for (int k = 0; k < 3; ++k) nb_s_[3 * pos + k] = int32_t(c_.cell_at(k, s));
  });
}

// Once a list change: the mesh's rest geometry, each element's at its
// position. Between changes the rest lengths stay as eased (sequence.hpp).
void Evaluator::lay_out_rest() {
  if (rest_stamp_ == lists_.stamp && lists_.stamp != 0) return;
  rest_stamp_ = lists_.stamp;
  for_edges([&](int64_t s, int64_t pos) {
    const RestGeometry r = edge_rest_geometry(c_, s);
    rest_e_[pos] = r.rest;
    width_e_[pos] = r.width;
  });
  for_triples([&](int64_t s, int64_t pos) {
    width_t_[pos] = triple_rest_geometry(c_, s).width;
  });
}

void Evaluator::use_local() {
  if (local_on_) return;
  local_on_ = true;
  for (auto* v : {&nb_t_, &nb_s_}) std::vector<int32_t>().swap(*v);  // the local tables name them now
  fit_local_tables(true);  // the lists' sizes, as the other arrays were at their first fit
  build_local(true);
}

// The own numbering: the free and hanging particles, then every other
// particle an element, a hanging link or a pair (a contact ghost) touches
// (found where the first search gives -1); then the elements', hanging links' and halo's tables.
void Evaluator::build_local(bool exact) {
  local_stamp_ = lists_.stamp;
  local_hanging_ = lists_.hanging.size();
  local_plan_ = halo_.plan_version();
  local_.list(lists_, tiling_, exact);
  number_elements(exact);
  map_hanging(exact);
  map_halo(exact);
  number_pairs();
}

// Self-contact's partners in the own numbering, kept beside the pair list
// (at each new list or numbering): the product reads them, never searches.
// A pair list built for older lists may name particles the numbering no
// longer has; the next refresh replaces it before any product.
void Evaluator::number_pairs() {
  pairs_numbered_ = self_.builds();
  pairs_missing_ = m_.self_contact ? self_.number_partners([this](int64_t q) { return local_.index_of(q); }) : 0;
}

// The elements' tables, filled in parallel (each entry by its own element),
// and the others they and the hanging links name, in between.
void Evaluator::number_elements(bool exact) {
  const int64_t ne = lists_.edges.size(), nt = lists_.triples.size(), ns = lists_.shears.size();
  const int64_t me = ne + lists_.ring_edges.size(), mt = nt + lists_.ring_triples.size(),
                ms = ns + lists_.ring_shears.size();
  auto slot = [](const ActiveList& own, const ActiveList& ring, int64_t pos) {
    return pos < own.size() ? own.items[size_t(pos)] : ring.items[size_t(pos - own.size())];
  };
  // f(table, k, id) for the element at pos (its table entries, its k-th particle).
  auto edge = [&](int64_t pos, auto&& f) {
    edge_particles(slot(lists_.edges, lists_.ring_edges, pos), [&](int k, int64_t id) { f(&lo_e_[2 * pos], k, id); });
  };
  auto triple = [&](int64_t pos, auto&& f) {
    triple_particles(slot(lists_.triples, lists_.ring_triples, pos),
                     [&](int k, int64_t id) { f(&lo_t_[3 * pos], k, id); });
  };
  auto cell = [&](int64_t pos, auto&& f) {
    cell_particles(slot(lists_.shears, lists_.ring_shears, pos), [&](int k, int64_t id) { f(&lo_s_[4 * pos], k, id); });
  };
  // Over every element's particles: in parallel (each entry its element's),
  // or in list order on this thread (a serial region would allocate its team).
  auto each = [&](bool parallel, auto&& f) {
    if (parallel) {
#pragma omp parallel
      {
#pragma omp for schedule(static) nowait
        for (int64_t pos = 0; pos < me; ++pos) edge(pos, f);
#pragma omp for schedule(static) nowait
        for (int64_t pos = 0; pos < mt; ++pos) triple(pos, f);
#pragma omp for schedule(static) nowait
        for (int64_t pos = 0; pos < ms; ++pos) cell(pos, f);
      }
    } else {
      for (int64_t pos = 0; pos < me; ++pos) edge(pos, f);
      for (int64_t pos = 0; pos < mt; ++pos) triple(pos, f);
      for (int64_t pos = 0; pos < ms; ++pos) cell(pos, f);
    }
  };
  each(true, [&](int32_t* at, int k, int64_t id) { at[k] = int32_t(local_.index_of_listed(id)); });
  int64_t others = 0;
  each(false, [&](int32_t* at, int k, int64_t) { others += at[k] < 0; });
  auto unlisted = [&](int64_t id) { return local_.index_of_listed(id) < 0; };
  for (const HangingLink& g : lists_.hanging) others += unlisted(g.a) + unlisted(g.b);
  // Self-contact's partners on other ranks: the product reads their v.
  const std::vector<int64_t>& partners = self_.ghost_partners();
  others += int64_t(partners.size());
  local_.reserve_others(size_t(others), exact);
  each(false, [&](int32_t* at, int k, int64_t id) {
    if (at[k] < 0) local_.add_other(id);
  });
  for (const HangingLink& g : lists_.hanging)
    for (int64_t e : {g.a, g.b})
      if (unlisted(e)) local_.add_other(e);
  for (int64_t q : partners)
    if (unlisted(q)) local_.add_other(q);
  local_.seal();
  each(true, [&](int32_t* at, int k, int64_t id) {
    if (at[k] < 0) at[k] = int32_t(local_.index_of(id));
  });
}

// Each hanging link's h, a and b; and the scratch that carries results to
// the ends: 3 a local particle, all zero between uses, held once the lists
// have room for hanging particles.
void Evaluator::map_hanging(bool exact) {
  const size_t nh = lists_.hanging.size();
  LocalNumbering::room(hang_lo_, lists_.hanging, 3, exact);
  hang_lo_.resize(3 * nh);
  for (size_t i = 0; i < nh; ++i) {
    const HangingLink& g = lists_.hanging[i];
    hang_lo_[3 * i] = int32_t(local_.index_of(g.h));
    hang_lo_[3 * i + 1] = int32_t(local_.index_of(g.a));
    hang_lo_[3 * i + 2] = int32_t(local_.index_of(g.b));
  }
  if (lists_.hanging.capacity() > 0) {
    const size_t room = 3 * local_capacity();
    if (exact ? hpend_lo_.capacity() != room : hpend_lo_.capacity() < room) {
      std::vector<double> fresh;
      fresh.reserve(room);
      hpend_lo_.swap(fresh);
    }
    hpend_lo_.assign(room, 0.0);
  }
}

// The halo plan's particles, sent and received, as local indices (-1: none
// here). The plan's visitors capture one reference each: a std::function
// holds that without allocating.
void Evaluator::map_halo(bool exact) {
  int64_t counts[2] = {0, 0};  // received, sent
  halo_.plan([&counts](int64_t, bool send) { ++counts[send]; });
  const size_t received = size_t(counts[0]), sent = size_t(counts[1]);
  fit(halo_send_, sent, sent, exact, int32_t(-1));
  fit(halo_recv_, received, received, exact, int32_t(-1));
  struct {
    const LocalNumbering& local;
    int32_t* at[2];  // the next receive's, send's entry
    void operator()(int64_t id, bool send) { *at[send]++ = int32_t(local.index_of(id)); }
  } place{local_, {halo_recv_.data(), halo_send_.data()}};
  halo_.plan([&place](int64_t id, bool send) { place(id, send); });
}

void Evaluator::interpolate_hanging_local(double* x) const {
  const std::vector<HangingLink>& hl = lists_.hanging;
  for (size_t i = hl.size(); i-- > 0;) {  // coarsest sides first: their ends are final
    const int64_t h = hang_lo_[3 * i], a = hang_lo_[3 * i + 1], b = hang_lo_[3 * i + 2];
    const double t = hl[i].t;
    for (int k = 0; k < 3; ++k) x[3 * h + k] = (1 - t) * x[3 * a + k] + t * x[3 * b + k];
  }
}

// A warp triple bends about the weft tangent, a weft triple about minus the
// warp tangent: both then count bending towards -normal as positive. The
// other yarn's tangent, less its part along the line's own: the axis is
// then normal to the line, so its edges stay clear of it (an edge along the
// axis leaves the angle undefined: a corner folded onto its diagonal
// neighbour laid one there). On an unsheared cloth nothing changes.
void Evaluator::freeze_bend_axes(const double* x1, const int32_t* slot) {
  list_rows(false);
  axes_stale_ = false;
  auto tangent = [&](int64_t p, int d) {
    const int64_t a = c_.prev_at(d, p) >= 0 ? c_.prev_at(d, p) : p;
    const int64_t b = c_.next_at(d, p) >= 0 ? c_.next_at(d, p) : p;
    V t = at(x1, slot_in(slot, b)) - at(x1, slot_in(slot, a));
    const double len = std::sqrt(dot(t, t));
    return len > 0 ? (1.0 / len) * t : V{0, 0, 0};
  };
  auto axis = [](const V& other, const V& own) {
    const V a = other - dot(other, own) * own;
    const double len = std::sqrt(dot(a, a));
    return len > 1e-3 ? (1.0 / len) * a : other;
  };
  // Each triple's own entry: any schedule writes the same numbers.
  for_triples([&](int64_t s, int64_t pos) {
    const int64_t p = s >> 1;
    const V warp = tangent(p, 0), weft = tangent(p, 1);
    store3((s & 1) == 0 ? axis(weft, warp) : -1.0 * axis(warp, weft), &axis_t_[3 * pos]);
  });
}

// ---- pass 1: element forces and band costs -------------------------------

void Evaluator::edge_forces(int64_t s, int64_t pos, const double* z, double* settle) {
  V g[2];
  const double L = edge_length(at(z, s >> 1), at(z, edge_far(pos)), g);
  edge_band(s, pos, L, g, z, settle);
}

void Evaluator::edge_four(const ItemRun& run, int64_t k, const double* z, EdgeFour& e, int64_t ends[4][2]) const {
  for (int l = 0; l < 4; ++l) {
    ends[l][0] = run.items[k + l] >> 1;
    ends[l][1] = edge_far(run.base + k + l);
    e.a[l] = at(z, ends[l][0]);
    e.b[l] = at(z, ends[l][1]);
  }
}

void Evaluator::edge_forces(const ItemRun& run, const double* z, double* settle) {
  in_fours(
      run,
      [&](int64_t k) {
        EdgeFour e;
        int64_t ends[4][2];
        edge_four(run, k, z, e, ends);
        V g[4][2];
        double L[4];
        edge_length_four(e, g, L);
#if DRAPE_LANES
        edge_bands(run, k, L, g, z, settle);
#else
        for (int l = 0; l < 4; ++l) edge_band(run.items[k + l], run.base + k + l, L[l], g[l], z, settle);
#endif
      },
      [&](int64_t k) { edge_forces(run.items[k], run.base + k, z, settle); });
}

void Evaluator::edge_band(int64_t s, int64_t pos, double L, const V g[2], const double* z, double* settle) {
  const int d = int(s & 1);
  const double L0 = rest_e_[pos], w = width_e_[pos];
  const BandValue bv = m_.stretch[d].at(L / L0 - 1.0);  // once: the power law is costly
  const Band::Stop st = m_.stretch[d].stop(anc_e_[pos], bv);
  active_.note(0, pos, L / L0 - 1.0, bv, st);
  const double f = settle ? (settle[c_.force_index(0, s)] = st.f) : z[c_.force_index(0, s)];
  if (settle && keep_) edge_kept(std::max(0.0, st.f), st.df_dq / L0, &kg_e_[kKgEdge * pos]);
  put(&buf_e_[kEdgeEntry * pos], g[1], f * w);
  const BandExcess ex = m_.use_stretch ? Band::excess(f, bv) : BandExcess{};
  const double lam = w / m_.force_scale;
  const double sigma = ex.r * lam, mem = (f - st.f) * lam;
  cost_e_[pos] = 0.5 * (sigma * sigma + m_.memory * mem * mem);
  if (!gq_e_.empty()) {  // a gradient's slopes (evaluate with one)
    gq_e_[pos] = (sigma * ex.dr_dq - m_.memory * mem * st.df_dq) * lam / L0;
    gf_e_[pos] = (sigma + m_.memory * mem) * lam;
  }
}

#if DRAPE_LANES
void Evaluator::edge_bands(const ItemRun& run, int64_t k, const double L[4], const V g[4][2], const double* z,
                           double* settle) {
  const int64_t* s = run.items + k;
  const int64_t pos = run.base + k;
  const D4 L0 = loadu4(&rest_e_[pos]), w = loadu4(&width_e_[pos]);
  const D4 q = loadu4(L) / L0 - splat4(1.0);
  double rev[4], f[4];
  for (int l = 0; l < 4; ++l) rev[l] = m_.stretch[s[l] & 1].reversal();
  const BandFour b4 = stretch_four(m_.stretch, s, q);  // once: the power law is costly
  const StopFour st = band_stop4(loadu4(&anc_e_[pos]), loadu4(rev), b4);
  for (int l = 0; l < 4; ++l) {
    const Band::Stop stl{st.f[l], st.df_dq[l]};
    if (active_.enabled()) active_.note(0, pos + l, q[l], lane_value(b4, l), stl);
    const int64_t t = c_.force_index(0, s[l]);
    f[l] = settle ? (settle[t] = stl.f) : z[t];
    if (settle && keep_)
      edge_kept(std::max(0.0, stl.f), stl.df_dq / L0[l], &kg_e_[kKgEdge * (pos + l)]);
    put(&buf_e_[kEdgeEntry * (pos + l)], g[l][1], f[l] * w[l]);
  }
  const bool slopes = !gq_e_.empty();  // a gradient's slopes (evaluate with one)
  band_costs4(b4, st, loadu4(f), w / splat4(m_.force_scale), m_.use_stretch, m_.memory, &L0, &cost_e_[pos],
              slopes ? &gq_e_[pos] : nullptr, slopes ? &gf_e_[pos] : nullptr);
}

void Evaluator::triple_bands(const ItemRun& run, int64_t k, const int64_t ids[4][3], const double th[4],
                             const V g[4][3], const double* z, double* settle) {
  const int64_t* s = run.items + k;
  const int64_t pos = run.base + k;
  double rest[4];
  for (int l = 0; l < 4; ++l) rest[l] = triple_rest_of(s[l], ids[l]);
  const D4 Lm = loadu4(rest), w = loadu4(&width_t_[pos]);
  const D4 q = loadu4(th) / Lm;
  double rev[4], f[4];
  for (int l = 0; l < 4; ++l) rev[l] = m_.bend[s[l] & 1].reversal();
  const BandFour b4 = bands_four(m_.bend[0], m_.bend[1], s, q);
  const StopFour st = band_stop4(loadu4(&anc_t_[pos]), loadu4(rev), b4);
  for (int l = 0; l < 4; ++l) {
    const Band::Stop stl{st.f[l], st.df_dq[l]};
    if (active_.enabled()) active_.note(1, pos + l, q[l], lane_value(b4, l), stl);
    const int64_t m = c_.force_index(1, s[l]);
    f[l] = settle ? (settle[m] = stl.f) : z[m];
    if ((settle && keep_) || narrow_) kept_bend(w[l] * stl.df_dq / Lm[l], g[l], &kg_t_[kKgTriple * (pos + l)]);
    if (narrow_)
      buf_t_[pos + l] = f[l] * w[l];
    else
      for (int i = 0; i < 3; ++i) put(&buf_t_[kTripleSlot * (pos + l) + 3 * i], g[l][i], f[l] * w[l]);
  }
  const bool slopes = !gq_t_.empty();
  band_costs4(b4, st, loadu4(f), w / (Lm * splat4(m_.force_scale)), m_.use_bend, m_.memory, &Lm, &cost_t_[pos],
              slopes ? &gq_t_[pos] : nullptr, slopes ? &gf_t_[pos] : nullptr);
}
#endif

void Evaluator::triple_forces(int64_t s, int64_t pos, const double* z, double* settle) {
  int64_t ids[3];
  triple_ids(s, pos, ids);
  V g[3];
  const V n = load3<double>(&axis_t_[3 * pos]);
  const double th = bend_angle(at(z, ids[0]), at(z, ids[1]), at(z, ids[2]), n, g);
  triple_band(s, pos, triple_rest_of(s, ids), th, g, z, settle);
}

void Evaluator::triple_four(const ItemRun& run, int64_t k, const double* z, TripleFour& t, int64_t ids[4][3]) const {
  for (int l = 0; l < 4; ++l) {
    const int64_t s = run.items[k + l];
    triple_ids(s, run.base + k + l, ids[l]);
    t.a[l] = at(z, ids[l][0]);
    t.b[l] = at(z, ids[l][1]);
    t.c[l] = at(z, ids[l][2]);
    t.n[l] = load3<double>(&axis_t_[3 * (run.base + k + l)]);
  }
}

void Evaluator::triple_forces(const ItemRun& run, const double* z, double* settle) {
  in_fours(
      run,
      [&](int64_t k) {
        TripleFour t;
        int64_t ids[4][3];
        triple_four(run, k, z, t, ids);
        V g[4][3];
        double sn[4], co[4], th[4];
        bend_terms_four(t, g, sn, co);
        turn_atan2_four(sn, co, th);
#if DRAPE_LANES
        triple_bands(run, k, ids, th, g, z, settle);
#else
        for (int l = 0; l < 4; ++l) {
          const int64_t s = run.items[k + l];
          triple_band(s, run.base + k + l, triple_rest_of(s, ids[l]), th[l], g[l], z, settle);
        }
#endif
      },
      [&](int64_t k) { triple_forces(run.items[k], run.base + k, z, settle); });
}

void Evaluator::triple_band(int64_t s, int64_t pos, double Lm, double th, const V g[3], const double* z,
                            double* settle) {
  const int d = int(s & 1);
  const double w = width_t_[pos];
  const BandValue bv = m_.bend[d].at(th / Lm);
  const Band::Stop st = m_.bend[d].stop(anc_t_[pos], bv);
  active_.note(1, pos, th / Lm, bv, st);
  const double f = settle ? (settle[c_.force_index(1, s)] = st.f) : z[c_.force_index(1, s)];
  if ((settle && keep_) || narrow_) kept_bend(w * st.df_dq / Lm, g, &kg_t_[kKgTriple * pos]);
  if (narrow_)
    buf_t_[pos] = f * w;
  else
    for (int k = 0; k < 3; ++k) put(&buf_t_[kTripleSlot * pos + 3 * k], g[k], f * w);
  const BandExcess ex = m_.use_bend ? Band::excess(f, bv) : BandExcess{};
  const double lam = w / (Lm * m_.force_scale);
  const double sigma = ex.r * lam, mem = (f - st.f) * lam;
  cost_t_[pos] = 0.5 * (sigma * sigma + m_.memory * mem * mem);
  if (!gq_t_.empty()) {  // a gradient's slopes (evaluate with one)
    gq_t_[pos] = (sigma * ex.dr_dq - m_.memory * mem * st.df_dq) * lam / Lm;
    gf_t_[pos] = (sigma + m_.memory * mem) * lam;
  }
}

void Evaluator::shear_forces(int64_t s, int64_t pos, const double* z, double* settle) {
  int64_t ids[4];
  cell_ids(s, pos, ids);
  const CellAt a = cell_at(ids, z);
  V g[4];
  const double phi = shear_cell(a.x, g);
  const double A = cell_area_of(ids);
  const BandValue bv = m_.shear.at(phi);
  const Band::Stop st = m_.shear.stop(anc_s_[pos], bv);
  active_.note(2, pos, phi, bv, st);
  const double f = settle ? (settle[c_.force_index(2, s)] = st.f) : z[c_.force_index(2, s)];
  if ((settle && keep_) || narrow_) kept_gradients(A * st.df_dq, g, 4, &kg_s_[kKgCell * pos]);
  if (narrow_)
    buf_s_[pos] = f * A;
  else
    for (int k = 0; k < 4; ++k) put(&buf_s_[kShearSlot * pos + 3 * k], g[k], f * A);
  const BandExcess ex = m_.use_shear ? Band::excess(f, bv) : BandExcess{};
  const double lam = A / (std::sqrt(A) * m_.force_scale);
  const double sigma = ex.r * lam, mem = (f - st.f) * lam;
  cost_s_[pos] = 0.5 * (sigma * sigma + m_.memory * mem * mem);
  if (!gq_s_.empty()) {  // a gradient's slopes (evaluate with one)
    gq_s_[pos] = (sigma * ex.dr_dq - m_.memory * mem * st.df_dq) * lam;
    gf_s_[pos] = (sigma + m_.memory * mem) * lam;
  }
}

void Evaluator::shear_forces(const ItemRun& run, const double* z, double* settle) {
#if DRAPE_LANES
  in_fours(
      run,
      [&](int64_t k) {
        double area[4], phi[4], sn[4][4], co[4][4];
        V g[4][4];
        for (int l = 0; l < 4; ++l) {
          int64_t ids[4];
          cell_ids(run.items[k + l], run.base + k + l, ids);
          shear_cell_terms(cell_at(ids, z).x, g[l], sn[l], co[l]);
          area[l] = cell_area_of(ids);
        }
        shear_angles_four(sn, co, phi);
        shear_bands(run, k, area, phi, g, z, settle);
      },
      [&](int64_t k) { shear_forces(run.items[k], run.base + k, z, settle); });
#else
  for (int64_t k = run.begin; k < run.end; ++k) shear_forces(run.items[k], run.base + k, z, settle);
#endif
}

#if DRAPE_LANES
void Evaluator::shear_bands(const ItemRun& run, int64_t k, const double area[4], const double phi[4],
                            const V g[4][4], const double* z, double* settle) {
  const int64_t* s = run.items + k;
  const int64_t pos = run.base + k;
  double root[4];
  for (int l = 0; l < 4; ++l) root[l] = std::sqrt(area[l]);
  const D4 A = loadu4(area), rest = loadu4(root);
  const int64_t one[4] = {0, 0, 0, 0};  // one band for every cell
  const BandFour b4 = bands_four(m_.shear, m_.shear, one, loadu4(phi));
  const StopFour st = band_stop4(loadu4(&anc_s_[pos]), splat4(m_.shear.reversal()), b4);
  double f[4];
  for (int l = 0; l < 4; ++l) {
    const Band::Stop stl{st.f[l], st.df_dq[l]};
    if (active_.enabled()) active_.note(2, pos + l, phi[l], lane_value(b4, l), stl);
    const int64_t t = c_.force_index(2, s[l]);
    f[l] = settle ? (settle[t] = stl.f) : z[t];
    if ((settle && keep_) || narrow_) kept_gradients(A[l] * stl.df_dq, g[l], 4, &kg_s_[kKgCell * (pos + l)]);
    if (narrow_)
      buf_s_[pos + l] = f[l] * A[l];
    else
      for (int i = 0; i < 4; ++i) put(&buf_s_[kShearSlot * (pos + l) + 3 * i], g[l][i], f[l] * A[l]);
  }
  const bool slopes = !gq_s_.empty();
  band_costs4(b4, st, loadu4(f), A / (rest * splat4(m_.force_scale)), m_.use_shear, m_.memory, nullptr,
              &cost_s_[pos], slopes ? &gq_s_[pos] : nullptr, slopes ? &gf_s_[pos] : nullptr);
}
#endif

// ---- pass 2: Newton residual per free particle ---------------------------

double Evaluator::particle_residual(int64_t p, int64_t pos, const GatherRow& row, const double* z, double* rho,
                                    const InertiaTerms& it, const double* passed) {
  if (!m_.use_newton) {
    rho[0] = rho[1] = rho[2] = 0;
    return 0;
  }
  const double* x = z + 3 * p;
  const double* x1 = c_.x1_at(p);
  const double* x2 = c_.x2_at(p);
  const double ca = it.accel, ratio = it.ratio, mass = c_.mass_at(p);
  const double cd = it.drag;
  double fc[3];
  contact_force(m_.contact, x, fc);
  friction_force(m_.contact, x, x1, fc);
  if (m_.self_contact) self_.add_force(pos, p, z, fc);
  double r[3];
  for (int k = 0; k < 3; ++k)
    r[k] = mass * (ca * (x[k] - x1[k] - ratio * (x1[k] - x2[k])) + cd * (x[k] - x1[k]) - m_.gravity[k]) -
           fc[k];
  gather_vector(row, r);
  if (passed)  // forces passed on by hanging particles (zero elsewhere)
    for (int k = 0; k < 3; ++k) r[k] += passed[k];
  const double inv = it.inv_scale;
  for (int k = 0; k < 3; ++k) rho[k] = r[k] * inv;
  return 0.5 * (rho[0] * rho[0] + rho[1] * rho[1] + rho[2] * rho[2]);
}

// ---- pass 3: element gradient contributions ------------------------------

namespace {
// Zero for particles without an equation (fixed); a hanging particle's is
// its ends' interpolated (hanging_residuals).
inline bool has_residual(const Cloth& c, int64_t p) { return c.free(p) || (c.flags[p] & kHanging); }
inline V residual_of(const Cloth& c, const std::vector<double>& rho, int64_t p) {
  return has_residual(c, p) ? load3<double>(&rho[3 * p]) : V{0, 0, 0};
}
}  // namespace

void Evaluator::edge_gradient(int64_t s, int64_t pos, const double* z, double* grad) {
  const int64_t p = s >> 1;
  const int64_t q = edge_far(pos);
  const V ra = residual_of(c_, rho_grid_, p), rb = residual_of(c_, rho_grid_, q);
  V g[2], hv;
  edge_length_hv(at(z, p), at(z, q), rb - ra, g, hv);
  edge_gradient_out(s, pos, ra, rb, g, hv, z, grad);
}

void Evaluator::edge_gradient(const ItemRun& run, const double* z, double* grad) {
  in_fours(
      run,
      [&](int64_t k) {
        EdgeFour e;
        int64_t ends[4][2];
        edge_four(run, k, z, e, ends);
        V ra[4], rb[4], v[4], g[4][2], hv[4];
        for (int l = 0; l < 4; ++l) {
          ra[l] = residual_of(c_, rho_grid_, ends[l][0]);
          rb[l] = residual_of(c_, rho_grid_, ends[l][1]);
          v[l] = rb[l] - ra[l];
        }
        double L[4];
        edge_length_hv_four(e, v, g, L, hv);
        for (int l = 0; l < 4; ++l)
          edge_gradient_out(run.items[k + l], run.base + k + l, ra[l], rb[l], g[l], hv[l], z, grad);
      },
      [&](int64_t k) { edge_gradient(run.items[k], run.base + k, z, grad); });
}

// hv: the length's Hessian times (rb - ra).
void Evaluator::edge_gradient_out(int64_t s, int64_t pos, const V& ra, const V& rb, const V g[2], const V& hv,
                                  const double* z, double* grad) {
  const double w = width_e_[pos], f = z[c_.force_index(0, s)];
  const double fw = f * w / m_.force_scale, gq = gq_e_[pos];
  put(&buf_e_[kEdgeEntry * pos], fw * hv + gq * g[1], 1.0);  // the first end's is (-fw) hv + gq g[0]
  if (double* o = force_entry(grad, 0, s, pos)) *o = w * (dot(g[0], ra) + dot(g[1], rb)) / m_.force_scale + gf_e_[pos];
}

void Evaluator::triple_gradient(int64_t s, int64_t pos, const double* z, double* grad) {
  int64_t ids[3];
  triple_ids(s, pos, ids);
  V r[3];
  for (int k = 0; k < 3; ++k) r[k] = residual_of(c_, rho_grid_, ids[k]);
  V g[3], hr[3];
  bend_gradient_hv(at(z, ids[0]), at(z, ids[1]), at(z, ids[2]), load3<double>(&axis_t_[3 * pos]), r, g, hr);
  triple_gradient_out(s, pos, r, g, hr, z, grad);
}

void Evaluator::triple_gradient(const ItemRun& run, const double* z, double* grad) {
  in_fours(
      run,
      [&](int64_t k) {
        TripleFour t;
        int64_t ids[4][3];
        triple_four(run, k, z, t, ids);
        V r[4][3], g[4][3], hr[4][3];
        for (int l = 0; l < 4; ++l)
          for (int i = 0; i < 3; ++i) r[l][i] = residual_of(c_, rho_grid_, ids[l][i]);
        bend_gradient_hv_four(t, r, g, hr);
        for (int l = 0; l < 4; ++l) triple_gradient_out(run.items[k + l], run.base + k + l, r[l], g[l], hr[l], z, grad);
      },
      [&](int64_t k) { triple_gradient(run.items[k], run.base + k, z, grad); });
}

void Evaluator::triple_gradient_out(int64_t s, int64_t pos, const V r[3], const V g[3], const V hr[3],
                                    const double* z, double* grad) {
  const double w = width_t_[pos], f = z[c_.force_index(1, s)];
  const double fw = f * w / m_.force_scale, gq = gq_t_[pos];
  double gr = 0;
  for (int k = 0; k < 3; ++k) {
    put(&buf_t_[kTripleSlot * pos + 3 * k], fw * hr[k] + gq * g[k], 1.0);
    gr += dot(g[k], r[k]);
  }
  if (double* o = force_entry(grad, 1, s, pos)) *o = w * gr / m_.force_scale + gf_t_[pos];
}

void Evaluator::shear_gradient(int64_t s, int64_t pos, const double* z, double* grad) {
  int64_t ids[4];
  cell_ids(s, pos, ids);
  const CellAt a = cell_at(ids, z);
  V r[4];
  for (int k = 0; k < 4; ++k) r[k] = residual_of(c_, rho_grid_, ids[k]);
  V g[4], hr[4];
  shear_cell_hv(a.x, r, g, hr);
  const double A = cell_area_of(ids), f = z[c_.force_index(2, s)];
  const double fa = f * A / m_.force_scale, gq = gq_s_[pos];
  double gr = 0;
  for (int k = 0; k < 4; ++k) {
    put(&buf_s_[kShearSlot * pos + 3 * k], fa * hr[k] + gq * g[k], 1.0);
    gr += dot(g[k], r[k]);
  }
  if (double* o = force_entry(grad, 2, s, pos)) *o = A * gr / m_.force_scale + gf_s_[pos];
}

void Evaluator::shear_gradient(const ItemRun& run, const double* z, double* grad) {
#if DRAPE_LANES
  in_fours(
      run, [&](int64_t k) { shear_gradient_four(run, k, z, grad); },
      [&](int64_t k) { shear_gradient(run.items[k], run.base + k, z, grad); });
#else
  for (int64_t k = run.begin; k < run.end; ++k) shear_gradient(run.items[k], run.base + k, z, grad);
#endif
}

#if DRAPE_LANES
// shear_gradient's arithmetic cell by cell, lane by lane.
void Evaluator::shear_gradient_four(const ItemRun& run, int64_t k, const double* z, double* grad) {
  const int64_t* s = run.items + k;
  const int64_t pos = run.base + k;
  V x[4][4], r[4][4];  // corner, cell
  double f[4], area[4];
  for (int l = 0; l < 4; ++l) {
    int64_t ids[4];
    cell_ids(s[l], pos + l, ids);
    for (int c = 0; c < 4; ++c) {
      x[c][l] = at(z, ids[c]);
      r[c][l] = residual_of(c_, rho_grid_, ids[c]);
    }
    f[l] = z[c_.force_index(2, s[l])];
    area[l] = cell_area_of(ids);
  }
  V4 X[4], R[4], G[4], H[4];
  for (int c = 0; c < 4; ++c) {
    X[c] = lanes4(x[c]);
    R[c] = lanes4(r[c]);
  }
  shear_cells_hv_four(X, R, G, H);
  const D4 A = loadu4(area), scale = splat4(m_.force_scale);
  const D4 fa = loadu4(f) * A / scale, gq = loadu4(&gq_s_[pos]);
  D4 gr = splat4(0.0);
  V4 out[4];
  for (int c = 0; c < 4; ++c) {
    out[c] = fa * H[c] + gq * G[c];
    gr = gr + dot(G[c], R[c]);
  }
  store_fours12(out, &buf_s_[kShearSlot * pos]);
  const D4 fg = A * gr / scale + loadu4(&gf_s_[pos]);
  for (int l = 0; l < 4; ++l)
    if (double* o = force_entry(grad, 2, s[l], pos + l)) *o = fg[l];
}
#endif

// ---- pass 4: gather per free particle ------------------------------------

void Evaluator::particle_gradient(int64_t p, int64_t pos, const GatherRow& row, const double* z, double* grad,
                                  const InertiaTerms& it) {
  const double* rho = &rho_grid_[3 * p];
  double g[3] = {0, 0, 0};
  if (m_.use_newton) {
    double fc[3], jtr[3] = {0, 0, 0};
    contact_force(m_.contact, z + 3 * p, fc, rho, jtr);
    friction_force(m_.contact, z + 3 * p, c_.x1_at(p), fc, rho, jtr);
    if (m_.self_contact) self_.add_jtr(pos, p, z, rho_grid_.data(), jtr);
    const double mca = c_.mass_at(p) * it.inertia;
    for (int k = 0; k < 3; ++k) g[k] = (mca * rho[k] + jtr[k]) / m_.force_scale;
  }
  gather_vector(row, g);
  const int64_t o = particle_entry(p, pos);
  for (int k = 0; k < 3; ++k) grad[o + k] = g[k];
}

// ---- driver ---------------------------------------------------------------

CostTerms Evaluator::reduce_costs() {
  timed_region([&] { cost_tile_loops(); });
  return sum_cost_tiles();
}

void Evaluator::cost_tile_loops() {
  const size_t nt = lists_.tiles.size();
  double* out = partials_.data();
  tile_loop(lists_.particles, [&](int64_t, int64_t k) { return cost_p_[k]; }, out);
  // Element costs sit in list order: an owned element's position is its
  // place in its list.
  tile_loop(lists_.edges, [&](int64_t, int64_t k) { return cost_e_[k]; }, out + nt);
  tile_loop(lists_.triples, [&](int64_t, int64_t k) { return cost_t_[k]; }, out + 2 * nt);
  tile_loop(lists_.shears, [&](int64_t, int64_t k) { return cost_s_[k]; }, out + 3 * nt);
}

CostTerms Evaluator::sum_cost_tiles() {
  double sums[4];
  red_.sum_tiles(lists_.tiles, partials_.data(), 4, sums);
  return {sums[0], sums[1], sums[2], sums[3]};
}

void Evaluator::rebalance(ListCuts* const* cuts, int n) const {
  for (int k = 0; k < n; ++k)
    if (cuts[k] && ((k < 6 && k % 2 == 1) || pol_.schedule == Schedule::ActiveLists)) cuts[k]->rebalance();
}

// The cost pass: element forces and band costs, then each particle's
// residual (with `grid`, at z's indices too, for a gradient). settle: see
// settled_cost.
CostTerms Evaluator::cost_pass(double* z, double* settle, bool grid) {
  const InertiaTerms it = inertia_terms();
  elements_then_particles([&](const ItemRun& run) { edge_forces(run, z, settle); },
                          [&](const ItemRun& run) { triple_forces(run, z, settle); },
                          [&](const ItemRun& run) { shear_forces(run, z, settle); }, [&] { hanging_forces(z); },
                          [&](int64_t p, int64_t pos) {
                            double* rho = &rho_[3 * pos];
                            cost_p_[pos] = particle_residual(p, pos, rows_[pos], z, rho, it, passed_force(pos));
                            if (grid) std::copy(rho, rho + 3, &rho_grid_[3 * p]);
                          });
  clear_hanging(hres_);
  return reduce_costs();
}

CostTerms Evaluator::settled_cost(double* z) {
  cost_z_ = nullptr;
  list_rows();
  // The ring's elements are settled here too, from the same positions and
  // anchors as their owners': no force halo (ranks_agree checks the bits).
  refresh_pairs(z);
  halo_.exchange(z, Halo::kPositions);
  interpolate_hanging(z);
  const CostTerms cost = cost_pass(z, z, false);
  settled_ = keep_;  // the elements' kept numbers are z's now (the particles' are not)
  kg_ready_ = false;
  return cost;
}

// The elements' band slopes along dk/dx and derivatives by their forces
// (gq_*, gf_*) only serve a gradient: sized at the first evaluation that asks
// for one, so Newton's runs (settled_cost, products) never hold them. Once
// sized, every cost pass writes them, as it always did.
void Evaluator::size_slopes() {
  if (slopes_) return;
  widen();
  slopes_ = true;
  fit_slopes(true);
  rho_grid_.assign(3 * size_t(c_.grid.n()), 0.0);
}

void Evaluator::fit_slopes(bool exact) {
  const size_t n = size_t(c_.grid.n());
  const size_t ne = size_t(lists_.edges.size() + lists_.ring_edges.size());
  const size_t nt = size_t(lists_.triples.size() + lists_.ring_triples.size());
  const size_t ns = size_t(lists_.shears.size() + lists_.ring_shears.size());
  for (auto* v : {&gq_e_, &gf_e_}) fit(*v, ne, 2 * n, exact, 0.0);
  for (auto* v : {&gq_t_, &gf_t_}) fit(*v, nt, 2 * n, exact, 0.0);
  for (auto* v : {&gq_s_, &gf_s_}) fit(*v, ns, n, exact, 0.0);
}

CostTerms Evaluator::evaluate(double* z, double* grad) { return evaluate_as(z, grad, false); }

CostTerms Evaluator::evaluate_as(double* z, double* grad, bool compact) {
  compact_ = compact;
  if (grad && !fused_) {
    const CostTerms cost = cost_for_gradient(z);
    gradient_as(grad, compact);
    return cost;
  }
  cost_z_ = nullptr;
  list_rows();
  settled_ = false;
  kg_ready_ = kg_ready_ && !narrow_;  // narrow, the pass keeps the elements' numbers at z
  refresh_pairs(z);
  halo_.exchange(z, Halo::kAll, c_.layout, c_.slots());
  interpolate_hanging(z);
  if (!grad) return cost_pass(z, nullptr, false);
  size_slopes();
  return fused_cost_gradient(z, grad);
}

CostTerms Evaluator::cost_for_gradient(double* z) {
  list_rows();
  settled_ = false;
  refresh_pairs(z);
  halo_.exchange(z, Halo::kAll, c_.layout, c_.slots());
  interpolate_hanging(z);
  size_slopes();
  const CostTerms cost = cost_pass(z, nullptr, true);
  cost_z_ = z;
  return cost;
}

void Evaluator::gradient_at_last_cost(double* grad) { gradient_as(grad, false); }

// The gradient's length: z's, or the compact order's.
int64_t Evaluator::gradient_size() const { return compact_ ? compact_size() : c_.layout.size(); }

void Evaluator::gradient_as(double* grad, bool compact) {
  compact_ = compact;
  const InertiaTerms it = inertia_terms();
  if (!cost_z_) throw std::logic_error("gradient_at_last_cost: no cost_for_gradient before it");
  const double* z = cost_z_;
  cost_z_ = nullptr;
  halo_.exchange_particles(rho_grid_.data(), 3);
  hanging_residuals();
  const int64_t nz = gradient_size();
  parallel_for(nz, [&](int64_t k) { grad[k] = 0.0; });  // a non-unknown's gradient is 0 (tested)
  // The element passes and the particles' gathers in one parallel region,
  // as the cost pass (a fork and join each cost more than a small mesh's pass).
  elements_then_particles([&](const ItemRun& run) { edge_gradient(run, z, grad); },
                          [&](const ItemRun& run) { triple_gradient(run, z, grad); },
                          [&](const ItemRun& run) { shear_gradient(run, z, grad); }, [] {},
                          [&](int64_t p, int64_t pos) { particle_gradient(p, pos, rows_[pos], z, grad, it); });
  hanging_gradient(z, grad);
}

// The separate passes' work, each pass the same body on the same items (so
// each element's and particle's arithmetic is the same, and every sum in
// the same order), with barriers where a pass reads the one before.
CostTerms Evaluator::fused_cost_gradient(double* z, double* grad) {
  const InertiaTerms it = inertia_terms();
  auto cost_e = [&](const ItemRun& run) { edge_forces(run, z, nullptr); };
  auto cost_t = [&](const ItemRun& run) { triple_forces(run, z, nullptr); };
  auto cost_s = [&](const ItemRun& run) { shear_forces(run, z, nullptr); };
  auto residual = [&](int64_t p, int64_t pos) {
    double* rho = &rho_[3 * pos];
    cost_p_[pos] = particle_residual(p, pos, rows_[pos], z, rho, it, passed_force(pos));
    std::copy(rho, rho + 3, &rho_grid_[3 * p]);
  };
  auto grad_e = [&](const ItemRun& run) { edge_gradient(run, z, grad); };
  auto grad_t = [&](const ItemRun& run) { triple_gradient(run, z, grad); };
  auto grad_s = [&](const ItemRun& run) { shear_gradient(run, z, grad); };
  auto gather = [&](int64_t p, int64_t pos) { particle_gradient(p, pos, rows_[pos], z, grad, it); };
  ListCuts* cost_cuts[7] = {};
  ListCuts* grad_cuts[7] = {};
  element_cuts<decltype(cost_e), decltype(cost_t), decltype(cost_s)>(cost_cuts);
  element_cuts<decltype(grad_e), decltype(grad_t), decltype(grad_s)>(grad_cuts);
  cost_cuts[6] = &cuts_for<decltype(residual)>(lists_.particles);
  grad_cuts[6] = &cuts_for<decltype(gather)>(lists_.particles);
  const int64_t nz = gradient_size();
  timed_region([&](RegionTime& rt) {
    // Nothing reads or writes the gradient before the barriers below.
#pragma omp for schedule(static) nowait
    for (int64_t k = 0; k < nz; ++k) grad[k] = 0.0;  // a non-unknown's gradient is 0 (tested)
    element_loops(cost_e, cost_t, cost_s, cost_cuts);
    team_serial(rt, [&] { hanging_forces(z); });
    item_loops(lists_.particles, pol_, *cost_cuts[6], residual);
    team_serial(rt, [&] {
      clear_hanging(hres_);
      halo_.exchange_particles(rho_grid_.data(), 3);  // MPI: on the master thread
      hanging_residuals();
    });
    cost_tile_loops();  // reads the costs only: the passes after may overlap it
    element_loops(grad_e, grad_t, grad_s, grad_cuts);
#pragma omp barrier
    item_loops(lists_.particles, pol_, *grad_cuts[6], gather);
  });
  rebalance(cost_cuts, 7);
  rebalance(grad_cuts, 7);
  hanging_gradient(z, grad);
  return sum_cost_tiles();
}

// A hanging particle's gradient: its contact term and its elements'.
void Evaluator::hanging_gradient(const double* z, double* grad) {
  hanging_into_ends(grad, [&](int64_t h, const GatherRow& row, double* v) {
    double fc[3], jtr[3] = {0, 0, 0};
    contact_force(m_.contact, z + 3 * h, fc, &rho_grid_[3 * h], jtr);
    friction_force(m_.contact, z + 3 * h, c_.x1_at(h), fc, &rho_grid_[3 * h], jtr);
    for (int k = 0; k < 3; ++k) v[k] = jtr[k] / m_.force_scale;
    gather_vector(row, v);
  }, 1.0, 0.0);
}

// ---- AMRC hanging particles -------------------------------------------------

void Evaluator::interpolate_hanging(double* x, const int32_t* slot) const {
  const std::vector<HangingLink>& hl = lists_.hanging;
  for (auto g = hl.rbegin(); g != hl.rend(); ++g) {  // coarsest sides first: their ends are final
    const int64_t h = slot_in(slot, g->h), a = slot_in(slot, g->a), b = slot_in(slot, g->b);
    if (h < 0 || a < 0 || b < 0) continue;
    for (int k = 0; k < 3; ++k) x[3 * h + k] = (1 - g->t) * x[3 * a + k] + g->t * x[3 * b + k];
  }
}

void Evaluator::clear_hanging(std::vector<double>& a) { std::fill(a.begin(), a.end(), 0.0); }

namespace {
// v with exactly `room` entries' capacity (moved only when that changes) and
// `need` entries.
template <class T>
void hold(std::vector<T>& v, size_t room, size_t need, const T& fill) {
  if (v.capacity() != room) {
    std::vector<T> fresh;
    fresh.reserve(room);
    v.swap(fresh);
  }
  v.resize(need, fill);
}
}  // namespace

// Slots, not grid indices: the buffers follow the hanging links. A particle
// that is one link's h and another's end (forces move on up) or two links'
// end holds one slot; sorting the links' particles by id finds them.
void Evaluator::number_hanging_slots() {
  const std::vector<HangingLink>& hl = lists_.hanging;
  if (hl.capacity() == 0) return;  // a uniform mesh holds none of it
  // Held at the room the lists hold (hanging links, rows), so they move only
  // when the lists' own arrays do: never while stepping.
  const size_t nh = hl.size(), cap = hl.capacity(), np = size_t(lists_.particles.size());
  hold(hslot_, 3 * cap, 3 * nh, int32_t(-1));
  hold(hsort_, 3 * cap, 3 * nh, std::pair<int64_t, int32_t>{});
  hold(row_hslot_, rows_.capacity(), np, int32_t(-1));
  std::fill(row_hslot_.begin(), row_hslot_.end(), int32_t(-1));
  for (size_t i = 0; i < nh; ++i) {
    const HangingLink& g = hl[i];
    hsort_[3 * i] = {g.h, int32_t(3 * i)};
    hsort_[3 * i + 1] = {g.a, int32_t(3 * i + 1)};
    hsort_[3 * i + 2] = {g.b, int32_t(3 * i + 2)};
  }
  std::sort(hsort_.begin(), hsort_.end());
  int32_t next = int32_t(nh);  // the ends that do not hang, after the hanging ones
  for (size_t b = 0, e; b < hsort_.size(); b = e) {
    int32_t slot = -1;
    for (e = b; e < hsort_.size() && hsort_[e].first == hsort_[b].first; ++e)
      if (slot < 0 && hsort_[e].second % 3 == 0) slot = hsort_[e].second / 3;  // h of that link
    if (slot < 0) slot = next++;
    for (size_t k = b; k < e; ++k) hslot_[size_t(hsort_[k].second)] = slot;
    const int64_t pos = list_position(hsort_[b].first);
    if (pos >= 0) row_hslot_[size_t(pos)] = slot;
  }
  // All zero between passes, as when sized.
  const size_t slots = std::min(3 * cap, size_t(c_.grid.n()));  // 3 a link, and never more than the grid's
  for (auto* v : {&hres_, &hpend_}) {
    hold(*v, 3 * slots, 3 * size_t(next), 0.0);
    std::fill(v->begin(), v->end(), 0.0);
  }
}

// The force on a hanging particle (its elements' and the contact's; it has
// no mass of its own) acts on its ends, by the interpolation weights.
void Evaluator::hanging_forces(const double* z) {
  clear_hanging(hres_);
  for (size_t i = 0; i < lists_.hanging.size(); ++i) {  // finest first: forces move on up
    const HangingLink& g = lists_.hanging[i];
    const size_t sh = 3 * size_t(hslot_[3 * i]), sa = 3 * size_t(hslot_[3 * i + 1]), sb = 3 * size_t(hslot_[3 * i + 2]);
    double f[3], fc[3];
    contact_force(m_.contact, z + 3 * g.h, fc);
    friction_force(m_.contact, z + 3 * g.h, c_.x1_at(g.h), fc);
    for (int k = 0; k < 3; ++k) f[k] = hres_[sh + k] - fc[k];
    gather_vector(hanging_row(i), f);
    for (int k = 0; k < 3; ++k) {
      hres_[sa + k] += (1 - g.t) * f[k];
      hres_[sb + k] += g.t * f[k];
    }
  }
}

// What the elements see at a hanging particle: its ends' residuals,
// interpolated (the chain rule of the force it passes on).
void Evaluator::hanging_residuals() {
  const std::vector<HangingLink>& hl = lists_.hanging;
  for (auto g = hl.rbegin(); g != hl.rend(); ++g) {
    const V ra = residual_of(c_, rho_grid_, g->a), rb = residual_of(c_, rho_grid_, g->b);
    store3((1 - g->t) * ra + g->t * rb, &rho_grid_[3 * g->h]);
  }
}


// ---- diagonal scaling -----------------------------------------------------

void Evaluator::scaling_diagonal(double* z, double* diag) { diagonal_as(z, diag, false); }

// The unknowns' entries of a vector `out` laid out like the gradient.
template <class F>
void Evaluator::for_each_unknown_entry(double* out, F&& f) {
  if (compact_)
    parallel_for(compact_size(), [&](int64_t k) { f(out[k]); });
  else
    for_each_listed(lists_.unknown_spans, [&](int64_t k) { f(out[k]); });
}

void Evaluator::diagonal_as(double* z, double* diag, bool compact) {
  compact_ = compact;
  widen();
  list_rows();
  refresh_pairs(z);
  halo_.exchange(z, Halo::kAll, c_.layout, c_.slots());
  interpolate_hanging(z);
  const double F0 = m_.force_scale, inv2 = 1.0 / (F0 * F0);
  for_each_unknown_entry(diag, [](double& d) { d = 1.0; });
  // Per element and particle: geometric stiffness (f c |dk/dx| / L)^2 and
  // band stiffness (lambda * slope * dq/dx)^2, written to the first entry of
  // the particle's buffer entry; the element force's own diagonal directly.
  // A band only stiffens its element where the force lies outside it (the
  // exact Gauss-Newton diagonal); inside, the force is free at no cost.
  const double mu = m_.memory;
  auto band_slope = [mu](double anchor, const Band& b, double f, double q) {
    const double stop = b.stop(anchor, q).df_dq;
    const double r = b.excess(f, q).dr_dq;
    return std::sqrt(r * r + mu * stop * stop);
  };
  auto outside = [](const Band& b, double f, double q) { return b.excess(f, q).r != 0 ? 1.0 : 0.0; };
  for_edges([&](int64_t s, int64_t pos) {
    const int64_t p = s >> 1;
    const int d = int(s & 1);
    const int64_t q = edge_far(pos);
    V g[2];
    const double L = edge_length(at(z, p), at(z, q), g);
    const double L0 = rest_e_[pos], w = width_e_[pos], f = z[c_.force_index(0, s)];
    const double eps = L / L0 - 1;
    const double geo = f * w / L, band = w * band_slope(anc_e_[pos], m_.stretch[d], f, eps) / L0;
    buf_e_[kEdgeEntry * pos] = (2 * geo * geo + band * band) * inv2;  // both ends'
    const double nf = double(c_.free(p)) + double(c_.free(q));
    if (double* o = force_entry(diag, 0, s, pos)) *o = w * w * (nf + outside(m_.stretch[d], f, eps) + m_.memory) * inv2;
  });
  for_triples([&](int64_t s, int64_t pos) {
    const int d = int(s & 1);
    int64_t ids[3];
    triple_ids(s, pos, ids);
    V g[3];
    const V n = load3<double>(&axis_t_[3 * pos]);
    const double th = bend_angle(at(z, ids[0]), at(z, ids[1]), at(z, ids[2]), n, g);
    const double Lm = triple_rest(s, pos), w = width_t_[pos], f = z[c_.force_index(1, s)];
    const double slope =
        band_slope(anc_t_[pos], m_.bend[d], f, th / Lm) * w / (Lm * Lm);
    double nf = 0;
    for (int k = 0; k < 3; ++k) {
      const double g2 = dot(g[k], g[k]);
      const double geo = f * w * std::sqrt(g2) / Lm;
      buf_t_[kTripleSlot * pos + 3 * k] = (3 * geo * geo + slope * slope * g2) * inv2;
      nf += c_.free(ids[k]) ? g2 : 0;
    }
    const double lam = w / Lm;
    if (double* o = force_entry(diag, 1, s, pos))
      *o = (w * w * nf + lam * lam * (outside(m_.bend[d], f, th / Lm) + m_.memory)) * inv2;
  });
  for_shears([&](int64_t s, int64_t pos) {
    int64_t ids[4];
    cell_ids(s, pos, ids);
    const CellAt a = cell_at(ids, z);
    V g[4];
    const double phi = shear_cell(a.x, g);
    const double A = cell_area_at(s, pos), Lr = std::sqrt(A), f = z[c_.force_index(2, s)];
    const double slope = band_slope(anc_s_[pos], m_.shear, f, phi) * A / Lr;
    double nf = 0;
    for (int k = 0; k < 4; ++k) {
      const double g2 = dot(g[k], g[k]);
      const double geo = f * A * std::sqrt(g2) / Lr;
      buf_s_[kShearSlot * pos + 3 * k] = (4 * geo * geo + slope * slope * g2) * inv2;
      nf += c_.free(a.ids[k]) ? g2 : 0;
    }
    const double lam = A / Lr;
    if (double* o = force_entry(diag, 2, s, pos))
      *o = (A * A * nf + lam * lam * (outside(m_.shear, f, phi) + m_.memory)) * inv2;
  });
  const double ca = m_.inertia_coeff();
  for_each_item(lists_.particles, pol_, [&](int64_t p, int64_t pos) {
    double fc[3], slope = 0;
    contact_force(m_.contact, z + 3 * p, fc, nullptr, nullptr, &slope);
    slope += friction_trace(m_.contact, z + 3 * p, c_.x1_at(p)) / 3;
    if (m_.self_contact) slope += self_.slope_sum(pos, p, z) / 3;
    const double inertia = c_.mass_at(p) * ca + slope;
    double dsum = inertia * inertia * inv2;
    gather_diagonal(rows_[pos], dsum);
    const int64_t o = particle_entry(p, pos);
    for (int k = 0; k < 3; ++k) diag[o + k] = dsum;
  });
  hanging_into_ends(diag, [&](int64_t h, const GatherRow& row, double* v) {
    double fc[3], slope = 0;
    contact_force(m_.contact, z + 3 * h, fc, nullptr, nullptr, &slope);
    slope += friction_trace(m_.contact, z + 3 * h, c_.x1_at(h)) / 3;
    double dsum = slope * slope * inv2;
    gather_diagonal(row, dsum);
    v[0] = v[1] = v[2] = dsum;
  }, 2.0, 1.0);
  // An unknown nothing depends on has a zero gradient too: any scale will do.
  for_each_unknown_entry(diag, [](double& d) {
    if (!(d > 0)) d = 1.0;
  });
}

// ---- numeric gradient (reference mode) ------------------------------------

// Cost of the terms that one unknown at (ic, jc) can change: element forces
// are refreshed three particles around it, residuals and band costs two.
double Evaluator::window_cost(const double* z, int ic, int jc) {
  const Grid& gr = c_.grid;
  for (int i = std::max(0, ic - 3); i <= std::min(gr.ni - 1, ic + 3); ++i)
    for (int j = std::max(0, jc - 3); j <= std::min(gr.nj - 1, jc + 3); ++j) {
      const int64_t p = gr.id(i, j);
      for (int d = 0; d < 2; ++d) {
        if (c_.edge_on_at(2 * p + d)) edge_forces(2 * p + d, position_of(0, 2 * p + d), z);
        if (c_.triple_on_at(2 * p + d)) triple_forces(2 * p + d, position_of(1, 2 * p + d), z);
      }
      if (c_.shear_on_at(p)) shear_forces(p, position_of(2, p), z);
    }
  double sum = 0;
  for (int i = std::max(0, ic - 2); i <= std::min(gr.ni - 1, ic + 2); ++i)
    for (int j = std::max(0, jc - 2); j <= std::min(gr.nj - 1, jc + 2); ++j) {
      const int64_t p = gr.id(i, j);
      double rho[3];  // scratch: the window's own
      if (c_.free(p)) {
        const int64_t pos = list_position(p);
        sum += particle_residual(p, pos, row_of(p), z, rho, inertia_terms(), passed_force(pos));
      }
      for (int d = 0; d < 2; ++d) {
        if (c_.edge_on_at(2 * p + d)) sum += cost_e_[position_of(0, 2 * p + d)];
        if (c_.triple_on_at(2 * p + d)) sum += cost_t_[position_of(1, 2 * p + d)];
      }
      if (c_.shear_on_at(p)) sum += cost_s_[position_of(2, p)];
    }
  return sum;
}

CostTerms Evaluator::numeric_gradient(double* z, double* grad) {
  const CostTerms cost = evaluate(z, nullptr);
  const int64_t nz = c_.layout.size();
  zwork_.assign(z, z + nz);
  std::fill(grad, grad + nz, 0.0);
  const Grid& gr = c_.grid;
  // window_cost reaches elements by slot: each active one needs a list
  // position, which holds where one rank owns every tile (this mode's case).
  for (int64_t s = 0; s < 2 * gr.n(); ++s)
    if ((c_.edge_on_at(s) && position_of(0, s) < 0) || (c_.triple_on_at(s) && position_of(1, s) < 0) ||
        (s < gr.n() && c_.shear_on_at(s) && position_of(2, s) < 0))
      throw std::logic_error("numeric gradient: an active element in no list (it needs every tile on one rank)");
  const double hmin = std::min(gr.hi, gr.hj), F0 = m_.force_scale;
  auto diff = [&](int64_t u, int64_t p, double scale) {
    const double h = 1e-6 * (std::fabs(z[u]) + scale);
    zwork_[u] = z[u] + h;
    const double cp = window_cost(zwork_.data(), gr.i_of(p), gr.j_of(p));
    zwork_[u] = z[u] - h;
    const double cm = window_cost(zwork_.data(), gr.i_of(p), gr.j_of(p));
    zwork_[u] = z[u];
    grad[u] = (cp - cm) / (2 * h);
  };
  for (int64_t p : lists_.particles.items)
    for (int k = 0; k < 3; ++k) diff(3 * p + k, p, hmin);
  // An element's position in its list is its index there (this rank's own).
  const std::vector<int64_t>&e = lists_.edges.items, &t = lists_.triples.items, &c = lists_.shears.items;
  for (size_t k = 0; k < e.size(); ++k) diff(c_.force_index(0, e[k]), e[k] >> 1, F0 / width_e_[k]);
  for (size_t k = 0; k < t.size(); ++k) diff(c_.force_index(1, t[k]), t[k] >> 1, F0 * triple_rest(t[k], int64_t(k)) / width_t_[k]);
  for (size_t k = 0; k < c.size(); ++k) {
    const double A = cell_area_at(c[k], int64_t(k));
    diff(c_.force_index(2, c[k]), c[k], F0 * std::sqrt(A) / A);
  }
  // Leave the buffers as evaluate() would have: at z.
  evaluate(z, nullptr);
  return cost;
}

}  // namespace drape
