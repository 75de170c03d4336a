#pragma once
// Cloth-cloth contact (docs/design.md §1, Self-contact): two free particles
// that are not mesh neighbours and come closer than the pair distance
// D = 2 delta (each particle keeps the obstacles' contact layer delta about
// itself) are pushed apart along the line joining them, with the obstacles'
// penalty shape and stiffness over the layer D:
//   F_p = phi(D - d) n,  n = (x_p - x_q)/d,  F_q = -F_p.
// Pairs are found by a spatial hash from the positions of the last build,
// reaching out to 2D, and the list is rebuilt only once a particle has moved
// more than D/2 from where it was then: every pair closer than D now was
// closer than 2D then, so the list always holds every pair that acts, and
// the forces do not depend on when it was built (pairs beyond D add nothing).
// Each particle keeps its partners sorted by global id and gathers its own
// pair terms in that order: the same sums on any thread count (gather, never
// scatter). On several ranks a partner may be any free particle of another
// rank: at each build the halo lists those within the reach of this rank's
// (contact ghosts, Halo::plan_contact) with their positions, and refreshes
// their entries with the ordinary ghosts' from then on; every rank builds
// when one must (the largest move over all ranks), so the lists, and the
// sums, are those of one rank.
#include <cstdint>
#include <vector>

#include "mesh/active_lists.hpp"
#include "mesh/cloth.hpp"
#include "solver/contact.hpp"
#include "solver/halo.hpp"
#include "solver/memory_table.hpp"
#include "solver/reducer.hpp"

namespace drape {

// One pair's term at p: the force on p is f n; slope = df/dpenetration.
struct PairTerm {
  double n[3];
  double f = 0, slope = 0, d = 0;
};

class SelfContact {
 public:
  // Makes the pair list hold at positions x (free particles of `particles`):
  // rebuilt when the lists, the contact layer or its stiffness changed, or a
  // particle moved more than a quarter of the search reach since the last
  // build (over all ranks: collective, through red and halo). Returns true
  // if it rebuilt; then the contact ghosts' entries of x are not yet
  // current (the next exchange of positions brings them). Its arrays hold
  // the list's particles (by list position) and the contact ghosts, not the
  // grid: fitted when the lists change (fit.hpp's rule, at most the grid).
  bool refresh(const Cloth& c, const ActiveList& particles, uint64_t stamp, const Contact& contact, const double* x,
               const Reducer& red, const Halo& halo = no_halo());

  // Room for the particles of `particles` (a grid of n at most): grown
  // where short, or with `exact` made their size (grid sequencing's next
  // stage); refresh grows them too where the lists changed.
  void fit_to_lists(const ActiveList& particles, int64_t n, bool exact);
  // The pair distance D (0 before the first refresh).
  double distance() const { return dist_; }
  // Calls f(q) for each listed partner of the particle at list position
  // pos (none where pos < 0: a hanging particle), ascending global id.
  template <class F>
  void for_partners(int64_t pos, F&& f) const {
    if (listed_ == 0 || pos < 0) return;  // no pairs at all (no cache line of the per-particle arrays read)
    for (int32_t k = first_[pos]; k < first_[pos + 1]; ++k) f(id_of_hashed(partners_[k]));
  }
  // The term of pair (p, q) at positions x; false (t untouched) when apart.
  bool term(const double* x, int64_t p, int64_t q, PairTerm& t) const;

  // Below, p is a particle's grid id and pos its list position.
  // Adds the pairs' force on p to f.
  void add_force(int64_t pos, int64_t p, const double* x, double* f) const;
  // Adds -(dF/dx_p)^T r over the residuals of p and its partners (r: 3 per
  // particle): the self-contact part of the Newton cost's gradient at p.
  void add_jtr(int64_t pos, int64_t p, const double* x, const double* r, double* jtr) const;
  // K's part at p (its positive semi-definite normal term): sum over pairs
  // of slope n n^T (v_p - v_q), added to out.
  void add_product(int64_t pos, int64_t p, const double* x, const double* v, double* out) const;
  // The same with v in the own numbering (number_partners's): vp is p's 3
  // values, each partner's at its kept index.
  void add_product_local(int64_t pos, int64_t p, const double* x, const double* vp, const double* v,
                         double* out) const {
    if (listed_ == 0) return;
    for (int32_t k = first_[pos]; k < first_[pos + 1]; ++k) {
      const int32_t h = partners_[k];
      PairTerm t;
      if (term(x, p, id_of_hashed(h), t)) normal_product(t, vp, v + 3 * int64_t(local_of_hashed(h)), out);
    }
  }
  // Keeps each contact ghost partner's index in a rank's own numbering,
  // index_of(q): done when the list or the numbering changes, so that a
  // product never searches. A partner on this rank needs none: the own
  // numbering starts with the particle list, so its index is its list
  // position, the hashed index kept. Returns how many ghost partners have
  // none (index_of gave -1): 0 unless the numbering lacks a partner.
  template <class IndexOf>
  int64_t number_partners(IndexOf&& index_of) {
    if (ghost_lo_.size() < ghosts_.size()) ghost_lo_.resize(ghosts_.capacity());  // grows with ghosts_ only
    int64_t missing = 0;
    for (size_t g = 0; g < ghosts_.size(); ++g) {
      ghost_lo_[g] = partner_[g] ? int32_t(index_of(ghosts_[g])) : -1;
      missing += partner_[g] && ghost_lo_[g] < 0;
    }
    return missing;
  }
  // The least distance at x between a listed particle and one of its
  // partners (infinity with no pairs): exact while below the pair distance
  // (every such pair is listed), at least it otherwise. This rank's own.
  double closest(const ActiveList& particles, const double* x) const;
  // Sum of the pairs' slopes at p (the trace of K's diagonal block).
  double slope_sum(int64_t pos, int64_t p, const double* x) const;
  // K's blocks of row p: block(q, b) with b = slope n n^T for q = p and -b
  // for each partner q (every listed partner: a zero block when apart, so
  // the pattern changes with the list only).
  template <class Block>
  void blocks(int64_t pos, int64_t p, const double* x, Block&& block) const {
    for_partners(pos, [&](int64_t q) {
      PairTerm t;
      double b[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
      if (term(x, p, q, t))
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) b[3 * i + j] = t.slope * t.n[i] * t.n[j];
      block(p, b);
      for (double& v : b) v = -v;
      block(q, b);
    });
  }

  // Counts: builds so far (a stamp for assembled patterns), listed pairs
  // (each once per particle) of the last build.
  uint64_t builds() const { return builds_; }
  // Builds whose partners outgrew some thread's share of the list's room
  // and were searched again (list_pairs): the same lists, more time.
  uint64_t searched_twice() const { return searched_twice_; }
  int64_t listed() const { return listed_; }
  // The last build's contact ghosts that are partners (other ranks'
  // particles whose values this rank reads until the next build).
  int64_t contact_ghosts() const { return int64_t(kept_.size()); }
  const std::vector<int64_t>& ghost_partners() const { return kept_; }  // those, ascending
  void memory(MemoryTable& t) const;

 private:
  // Room for `hashed` particles in the hash (the list's and the contact
  // ghosts), as fit_to_lists.
  void fit_hash(int64_t hashed, int64_t n, bool exact);
  // The largest squared move of a listed particle since the last build.
  double worst_move(const ActiveList& particles, const double* x) const;
  void build(const Cloth& c, const ActiveList& particles, const double* x, const Halo& halo);
  void hash_particles();
  // Lists each particle's partners at first_ (counts and offsets) and
  // partners_, unsorted.
  void list_pairs(const Cloth& c, const ActiveList& particles);
  // The build's position of hashed particle h: the list's first (by list
  // position), then the contact ghosts (ascending id).
  const double* built_at(int64_t h) const {
    return h < own_ ? &xb_[3 * h] : &gx_[3 * (h - own_)];
  }
  // Calls f(q) for each particle q != p (p at list position pos) within the
  // search reach of p at the build's positions and not excluded as p's mesh
  // neighbour.
  template <class F>
  void candidates(const Cloth& c, const ActiveList& particles, int64_t pos, F&& f) const;
  int64_t bucket_of(int64_t cx, int64_t cy, int64_t cz) const;
  void cell_of(const double* x, int64_t cell[3]) const;
  // Adds a pair's slope n n^T (v_p - v_q) to out.
  static void normal_product(const PairTerm& t, const double* vp, const double* vq, double* out) {
    double nv = 0;
    for (int i = 0; i < 3; ++i) nv += t.n[i] * (vp[i] - vq[i]);
    for (int i = 0; i < 3; ++i) out[i] += t.slope * nv * t.n[i];
  }

  Contact contact_;
  double dist_ = 0, reach_ = 0, exclude2_ = 0;
  uint64_t stamp_ = 0, builds_ = 0, searched_twice_ = 0;
  int64_t buckets_ = 1;             // the last build's bucket count (a power of two)
  int64_t listed_ = 0;
  int64_t own_ = 0;                 // the list's particles at the last build
  std::vector<double> xb_;          // positions of the last build, 3 per list position
  std::vector<double> gx_;          // the contact ghosts' positions then (the build's scratch)
  // Per list position k: its partners are partners_[first_[k] .. first_[k+1]),
  // each a hashed index (built_at's: a list position, or own_ plus a contact
  // ghost's place), ascending by global id. One 32-bit number a pair stands
  // for both the partner's id and its index in the own numbering.
  std::vector<int32_t> first_;
  std::vector<int32_t> partners_;
  std::vector<int32_t> ghost_lo_;   // per contact ghost: its own-numbering index (partners only; number_partners)
  const ActiveList* particles_ = nullptr;  // the list the last build hashed
  int64_t id_of_hashed(int32_t h) const { return h < own_ ? particles_->items[size_t(h)] : ghosts_[size_t(h - own_)]; }
  int64_t local_of_hashed(int32_t h) const { return h < own_ ? h : ghost_lo_[size_t(h - own_)]; }
  std::vector<int32_t> bucket_start_, bucket_items_;  // the hash: hashed particles (built_at) by bucket
  std::vector<double> bucket_x_;    // their build positions in that order, 3 each (the build's scratch)
  std::vector<int64_t> ghosts_;     // the last build's contact ghosts, ascending
  std::vector<int64_t> kept_;       // those some listed particle has as a partner
  std::vector<char> partner_;       // per contact ghost: a partner (the build's scratch)
  // Narrows the halo's contact ghosts to the partners (kept_).
  void keep_partners(const Halo& halo);
};

}  // namespace drape
