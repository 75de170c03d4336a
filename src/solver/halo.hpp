#pragma once
// Ghost particles (docs/design.md §3): a rank computes the elements of its own tiles
// and of a ring one particle wide around them, whose contributions its own
// particles gather; those elements read particles up to two away. Before a
// vector laid out like z is read there, its ghost entries get their owners'
// values; so do the particle residuals before the gradient pass, which
// reads them at both ends of every element. The MPI version lives in src/decomp/halo_exchange; physics only
// sees this interface.
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
