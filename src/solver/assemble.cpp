// K assembled: the stiffness product's operator as 3 x 3 blocks over the
// free particles, for the multigrid preconditioner. Built row by row from
// each particle's gather row (the product's fixed order), so any thread
// count gives the same matrix. The blocks come from the numbers the
// diagonal kept and z (the products read the same): an edge's
//   B = w (T/L (I - u u^T) + slope/L0 u u^T)   (+B on its ends, -B across),
// a triple's or cell's factor g_a g_b^T, a particle's mass coefficient and
// contact normal term. Hanging particles fold onto their ends by their
// interpolation weights, K_free = P^T K P, as in the product.
#include <omp.h>

#include <algorithm>
#include <stdexcept>

#include "solver/cost.hpp"
#include "solver/multigrid/block_matrix.hpp"

namespace drape {

namespace {
// The slot at position pos of an element list (the ring's after this rank's).
inline int64_t slot_at(const ActiveList& own, const ActiveList& ring, int64_t pos) {
  return pos < own.size() ? own.items[pos] : ring.items[pos - own.size()];
}
// A free particle's share of a hanging particle's terms: its grid id and weight.
struct Share {
  int64_t id;
  double w;
};
// Equal ids' weights summed in the order met: the same sums whatever the
// ids' columns are.
void merge_shares(std::vector<Share>& s) {
  std::stable_sort(s.begin(), s.end(), [](const Share& a, const Share& b) { return a.id < b.id; });
  size_t o = 0;
  for (size_t k = 0; k < s.size(); ++k) {
    if (o > 0 && s[o - 1].id == s[k].id) s[o - 1].w += s[k].w;
    else s[o++] = s[k];
  }
  s.resize(o);
}
}  // namespace

// With global columns (several ranks) a hanging particle's ends may be
// other ranks' free particles: its shares then land in their columns, so
// a row folds in every hanging particle leaning on it, as on one rank.
void Evaluator::assembly_maps(uint64_t column_stamp) {
  if (asm_stamp_ == lists_.stamp && lists_.stamp != 0 && asm_hanging_ == lists_.hanging.size() &&
      asm_map_columns_ == column_stamp && !asm_index_.empty())
    return;
  asm_stamp_ = lists_.stamp;
  asm_hanging_ = lists_.hanging.size();
  asm_map_columns_ = column_stamp;
  const int32_t* global = asm_columns_;
  const ActiveList& pl = lists_.particles;
  asm_index_.assign(size_t(c_.grid.n()), -1);
  for (int64_t r = 0; r < pl.size(); ++r) asm_index_[pl.items[r]] = int32_t(r);
  // Each hanging particle as a combination of free rows, coarsest sides
  // first (their ends are final), as interpolate_hanging walks them.
  const std::vector<HangingLink>& hl = lists_.hanging;
  std::vector<std::vector<Share>> ex(hl.size());
  asm_hang_.assign(hl.empty() ? 0 : size_t(c_.grid.n()), -1);
  std::vector<int32_t>& hang_of = asm_hang_;
  for (size_t i = 0; i < hl.size(); ++i) hang_of[hl[i].h] = int32_t(i);
  auto add_end = [&](std::vector<Share>& out, int64_t e, double w) {
    if (global ? global[e] >= 0 : asm_index_[e] >= 0) out.push_back({e, w});
    else if (hang_of[e] >= 0)
      for (const Share& s : ex[hang_of[e]]) out.push_back({s.id, w * s.w});
    // fixed ends (one rank's columns: another rank's too): no unknown behind them
  };
  for (size_t k = hl.size(); k-- > 0;) {
    add_end(ex[k], hl[k].a, 1 - hl[k].t);
    add_end(ex[k], hl[k].b, hl[k].t);
    merge_shares(ex[k]);
  }
  hx_start_.assign(hl.size() + 1, 0);
  hx_.clear();
  for (size_t k = 0; k < hl.size(); ++k) {
    for (const Share& s : ex[k]) hx_.push_back({global ? global[s.id] : asm_index_[s.id], s.w});
    hx_start_[k + 1] = int64_t(hx_.size());
  }
  // The transpose: per free row of this rank, the hanging particles that lean on it.
  ht_start_.assign(size_t(pl.size()) + 1, 0);
  for (size_t k = 0; k < hl.size(); ++k)
    for (const Share& s : ex[k])
      if (asm_index_[s.id] >= 0) ++ht_start_[asm_index_[s.id] + 1];
  for (int64_t r = 0; r < pl.size(); ++r) ht_start_[r + 1] += ht_start_[r];
  ht_.assign(size_t(ht_start_[pl.size()]), {0, 0.0});
  std::vector<int64_t> fill(ht_start_.begin(), ht_start_.end() - 1);
  for (size_t k = 0; k < hl.size(); ++k)  // ascending k within a row: a fixed order
    for (const Share& s : ex[k])
      if (asm_index_[s.id] >= 0) ht_[fill[asm_index_[s.id]]++] = {int32_t(k), s.w};
  asm_pattern_ = false;
}

// Calls add(column row, weight, block) for every term of free row r, in a
// fixed order: the particle's own terms and elements, then those of each
// hanging particle that leans on it.
template <class Add>
void Evaluator::row_terms(int64_t r, Add&& add) const {
  // With global columns (several ranks): any rank's free particle has one.
  const int32_t* global = asm_columns_;
  auto columns = [&](int64_t p, double w, const double* blk) {
    if (global && global[p] >= 0) {
      add(global[p], w, blk);
      return;
    }
    const int32_t row = asm_index_[p];
    if (row >= 0) {
      add(row, w, blk);
      return;
    }
    const int32_t k = asm_hang_.empty() ? -1 : asm_hang_[p];
    if (k >= 0)  // a hanging particle: its ends' columns, by its weights
      for (int64_t e = hx_start_[k]; e < hx_start_[k + 1]; ++e) add(hx_[e].row, w * hx_[e].w, blk);
    // fixed, or (one rank's columns) another rank's: no unknown of this rank behind it
  };
  auto one = [&](int64_t p, int64_t pos, const GatherRow& g, double mass, double w) {
    double blk[9] = {mass, 0, 0, 0, mass, 0, 0, 0, mass};
    double kc[kKc];
    contact_terms(p, k_z_, kc);
    if (kc[3] > 0) {  // contact: slope n n^T, n the force's direction
      const double s = kc[4] / (kc[3] * kc[3]);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) blk[3 * i + j] += s * kc[i] * kc[j];
    }
    friction_block(m_.contact, k_z_ + 3 * p, c_.x1_at(p), blk);
    columns(p, w, blk);
    if (m_.self_contact) self_.blocks(pos, p, k_z_, [&](int64_t q, const double* b) { columns(q, w, b); });
    const int32_t* at = g.at;
    for (int d = 0; d < 2; ++d, at += GatherRow::kPerDirection) {
      for (int k = 0; k < 2; ++k)
        if (at[k] >= 0) {
          const int64_t pos = at[k] / kEdgeEntry, part = k;  // place 0: its first end
          const int64_t s = slot_at(lists_.edges, lists_.ring_edges, pos);
          const int64_t ends[2] = {s >> 1, edge_far(pos)};
          const EdgeStiffness ke = edge_stiffness_at(s, pos, k_z_);
          const double iv = 1.0 / ke.length;
          const double u[3] = {ke.e.x * iv, ke.e.y * iv, ke.e.z * iv};
          const double a = ke.width * ke.tension * iv, b = ke.width * ke.slope_per_rest - a;
          double B[9];
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) B[3 * i + j] = (i == j ? a : 0.0) + b * u[i] * u[j];
          columns(ends[part], w, B);
          for (double& x : B) x = -x;
          columns(ends[1 - part], w, B);
        }
      for (int k = 2; k < 5; ++k)
        if (at[k] >= 0) {
          const int64_t pos = at[k], part = k - 2;  // places 2-4: its parts 0-2
          int64_t ids[3];
          triple_ids(slot_at(lists_.triples, lists_.ring_triples, pos), pos, ids);
          double kg[1 + 3 * 3];  // the factor and the three gradients, as a cell's
          V3<double> g[3];
          kept_bend_gradients(&kg_t_[kKgTriple * pos], g);
          kg[0] = kg_t_[kKgTriple * pos];
          for (int i = 0; i < 3; ++i) kg[1 + 3 * i] = g[i].x, kg[2 + 3 * i] = g[i].y, kg[3 + 3 * i] = g[i].z;
          rank_one(kg, 3, int(part), ids, w, columns);
        }
    }
    for (int k = 0; k < 4; ++k)
      if (at[k] >= 0) {
        const int64_t pos = at[k], part = k;
        int64_t ids[4];
        cell_ids(slot_at(lists_.shears, lists_.ring_shears, pos), pos, ids);
        rank_one(&kg_s_[kKgCell * pos], 4, int(part), ids, w, columns);
      }
  };
  const int64_t p = lists_.particles.items[r];
  one(p, r, rows_[r], c_.mass_at(p) * m_.inertia_coeff(), 1.0);
  for (int64_t e = ht_start_[r]; e < ht_start_[r + 1]; ++e) {
    const size_t k = size_t(ht_[e].row);
    one(lists_.hanging[k].h, -1, hanging_row(k), 0.0, ht_[e].w);  // no mass at h
  }
}

// A triple's or cell's blocks in row `part`: factor g_part g_b^T.
template <class Columns>
void Evaluator::rank_one(const double* kg, int n, int part, const int64_t* ids, double w, Columns&& columns) {
  const double* ga = kg + 1 + 3 * part;
  for (int b = 0; b < n; ++b) {
    const double* gb = kg + 1 + 3 * b;
    double blk[9];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) blk[3 * i + j] = kg[0] * ga[i] * gb[j];
    columns(ids[b], w, blk);
  }
}

void Evaluator::assemble_stiffness(BlockMatrix& K, const std::vector<int32_t>* column_of, int64_t columns,
                                   uint64_t column_stamp) {
  list_rows();
  if (!keep_ || !kg_ready_)
    throw std::logic_error("Evaluator::assemble_stiffness: needs stiffness_diagonal's kept numbers");
  const int64_t rows = lists_.particles.size();
  asm_columns_ = column_of ? column_of->data() : nullptr;
  if (!column_of) columns = rows;
  assembly_maps(column_of ? column_stamp : 0);
  // The columns change with the lists, self-contact's pairs and the global
  // numbering only (new maps for the first and last clear asm_pattern_).
  if (!asm_pattern_ || K.rows != rows || asm_pairs_ != self_.builds()) {
    asm_pairs_ = self_.builds();
    build_pattern(K, rows, asm_scratch_, [&](int64_t r, auto&& push) {
      row_terms(r, [&](int32_t c, double, const double*) { push(c); });
    });
    asm_pattern_ = true;
  }
  asm_slots_.size(omp_get_max_threads(), columns);
#pragma omp parallel
  {
    // column -> its block in row r (no searches)
    std::vector<int64_t>& slot = asm_slots_.of[size_t(omp_get_thread_num())];
#pragma omp for schedule(static)
    for (int64_t r = 0; r < rows; ++r) {
      for (int64_t k = K.start[r]; k < K.start[r + 1]; ++k) slot[K.col[k]] = k;
      std::fill(K.val.begin() + 9 * K.start[r], K.val.begin() + 9 * K.start[r + 1], 0.0);
      row_terms(r, [&](int32_t c, double w, const double* blk) {
        double* out = &K.val[9 * slot[c]];
        for (int i = 0; i < 3; ++i)  // blk row-major, K's blocks column-major
          for (int j = 0; j < 3; ++j) out[entry(i, j)] += w * blk[3 * i + j];
      });
      for (int64_t k = K.start[r]; k < K.start[r + 1]; ++k) slot[K.col[k]] = -1;
    }
  }
  asm_columns_ = nullptr;
}

}  // namespace drape
