#pragma once
// Ghost particles (docs/design.md §3): a rank computes the elements of its own tiles
// and of a ring one particle wide around them, whose contributions its own
// particles gather; those elements read particles up to two away. Before a
// vector laid out like z is read there, its ghost entries get their owners'
// values; so do the particle residuals before the gradient pass, which
// reads them at both ends of every element. The MPI version lives in src/decomp/halo_exchange; physics only
// sees this interface.
#include <cstdint>
#include <vector>

namespace drape {

class Halo {
 public:
  enum Blocks { kPositions = 1, kForces = 2, kAll = 3 };
  virtual ~Halo() = default;
  // Refreshes the ghost entries of `z` (laid out like Cloth::z; with
  // kPositions alone, any array of 3 values per particle such as x1).
  virtual void exchange(double* z, int blocks) const = 0;
  // The same for an array of `per` values per particle (residuals).
  virtual void exchange_particles(double* a, int per) const = 0;
  // Contact ghosts (self-contact's partners on other ranks, docs/design.md
  // §1): from the positions x (3 per particle) of this rank's free
  // particles `own`, lists in `ghosts` (ascending) every free particle of
  // another rank within `reach` of one of them, and perhaps some further,
  // and writes their positions into x. From then on, until the next plan or
  // a new tile plan, exchange (with kPositions) and exchange_particles
  // refresh them too. Collective over the ranks. One rank: none.
  virtual void plan_contact(const std::vector<int64_t>& own, double reach, double* x,
                            std::vector<int64_t>& ghosts) const {
    (void)own, (void)reach, (void)x;
    ghosts.clear();
  }
  // Narrows the last plan to the contact ghosts `kept` (ascending, a subset
  // of its ghosts: the ones some particle of this rank reads) in the
  // exchanges from then on. Collective.
  virtual void keep_contact(const std::vector<int64_t>& kept) const { (void)kept; }
};

// One rank owning every tile: there are no ghosts.
class NoHalo : public Halo {
 public:
  void exchange(double*, int) const override {}
  void exchange_particles(double*, int) const override {}
};

inline const Halo& no_halo() {
  static const NoHalo none;
  return none;
}

}  // namespace drape
