#pragma once
// Ghost particles (docs/design.md §3): a rank computes the elements of its own tiles
// and of a ring one particle wide around them, whose contributions its own
// particles gather; those elements read particles up to two away. Before a
// vector laid out like z is read there, its ghost entries get their owners'
// values; so do the particle residuals before the gradient pass, which
// reads them at both ends of every element. The MPI version lives in src/decomp/halo_exchange; physics only
// sees this interface.
#include <cstdint>
#include <functional>
#include <vector>

#include "mesh/cloth.hpp"

namespace drape {

class Halo {
 public:
  enum Blocks { kPositions = 1, kForces = 2, kAll = 3 };
  virtual ~Halo() = default;
  // Refreshes the ghost entries of `z` (laid out like Cloth::z over the
  // whole grid, no slots; with kPositions alone, any array of 3 values per
  // grid particle).
  void exchange(double* z, int blocks) const { exchange(z, blocks, Layout{grid_particles(), grid_particles()}, nullptr); }
  // The same for z laid out as `layout`, its forces at slot[p] (Cloth::slots;
  // null: at p).
  virtual void exchange(double* z, int blocks, const Layout& layout, const int32_t* slot) const = 0;
  // The particles of the grid the exchanges run over.
  virtual int64_t grid_particles() const { return 0; }
  // The same for an array of `per` values per particle (residuals).
  virtual void exchange_particles(double* a, int per) const = 0;
  // Contact ghosts (self-contact's partners on other ranks, docs/design.md
  // §1): from the positions own_x (3 per particle, own's order) of this
  // rank's free particles `own`, lists in `ghosts` (ascending) every free
  // particle of another rank within `reach` of one of them, and perhaps
  // some further, and their positions in ghost_x (3 each, ghosts' order). From then on, until the next plan or
  // a new tile plan, exchange (with kPositions), exchange_particles and
  // exchange_at refresh them too (they are in plan()'s lists, and
  // plan_version() changes with each plan). Collective over the ranks. One
  // rank: none.
  virtual void plan_contact(const std::vector<int64_t>& own, const double* own_x, double reach,
                            std::vector<int64_t>& ghosts, std::vector<double>& ghost_x) const {
    (void)own, (void)own_x, (void)reach;
    ghosts.clear();
    ghost_x.clear();
  }
  // Narrows the last plan to the contact ghosts `kept` (ascending, a subset
  // of its ghosts: the ones some particle of this rank reads) in the
  // exchanges from then on. Collective.
  virtual void keep_contact(const std::vector<int64_t>& kept) const { (void)kept; }

  // Vectors in a rank's own numbering (LocalNumbering: 3 values a
  // particle, no grid-sized array). plan(f) calls f(id, true) for each
  // particle an exchange sends, then f(id, false) for each it receives, in
  // the order exchange_at packs and unpacks them; plan_version() changes
  // whenever that plan does.
  virtual void plan(const std::function<void(int64_t, bool)>& f) const { (void)f; }
  virtual uint64_t plan_version() const { return 0; }
  // The ghosts' 3 values of `a`: the plan's k-th sent particle is read at
  // a[3 send_at[k]] (sent as 0 where send_at[k] < 0: this rank holds no
  // entry for it, so nothing of its own reads it), the k-th received one
  // written at a[3 recv_at[k]] (dropped where < 0: nothing here reads it).
  virtual void exchange_at(double* a, const int32_t* send_at, const int32_t* recv_at) const {
    (void)a, (void)send_at, (void)recv_at;
  }
};

// One rank owning every tile: there are no ghosts.
class NoHalo : public Halo {
 public:
  using Halo::exchange;
  void exchange(double*, int, const Layout&, const int32_t*) const override {}
  void exchange_particles(double*, int) const override {}
};

inline const Halo& no_halo() {
  static const NoHalo none;
  return none;
}

}  // namespace drape
