#pragma once
// Newton through the bands' kinks: the active set of branches.
//
// Band::stop is piecewise smooth in the strain: clamped to the upper edge,
// clamped to the lower edge, or inside the band at `reversal` times the
// loading slope. Newton's tangent takes each element's slope on the branch
// it holds at z; an element that crosses to another branch within the step
// then has the wrong stiffness, by the reversal (5) or more, and the full
// step over- or undershoots. As plasticity's return mapping does, a trial
// point tells each element which branch it lands on: where that differs from
// z's, the element's stiffness at z is replaced by the secant of its stop
// force between z's strain and the trial's (for straight branches, the
// slopes of the two weighted by how much of the strain change lies on each:
// a generalized-Newton tangent), and the step is solved again from the same
// z with the same residual. An element once changed keeps its secant, from
// the latest trial, for the rest of that Newton iteration, so that a
// re-solve that falls back short of the kink does not swap it back.
//
// The evaluator notes each band element's strain, stop force and branch at
// every evaluation while recording (one slot for z, one for the trial):
// per element and its own position, so bitwise for any thread count.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "solver/band.hpp"

namespace drape {

class BandActiveSet {
 public:
  // Which part of the stop operator the force is on: 1 the upper edge, -1
  // the lower, 0 inside.
  static int branch(const BandValue& v, const Band::Stop& st) {
    return st.f >= v.hi ? 1 : (st.f <= v.lo ? -1 : 0);
  }

  // Off: no memory, nothing noted.
  void enable(bool on);
  bool enabled() const { return on_; }
  // Sized by the lists (kind 0 edges, 1 triples, 2 cells; `most` the grid's slots).
  void fit(int kind, size_t count, size_t most, bool exact);

  // Where the evaluations write: z's slot (from a Newton iteration's start
  // and after an accepted trial) or the trial's.
  void at_z() { slot_ = z_; }
  void at_trial() { slot_ = 1 - z_; }
  // The trial evaluated last is the new z.
  void accept_trial() { z_ = slot_; }
  // A new Newton iteration: no element has changed branch in it yet.
  void next_iteration() { ++stamp_; }

  void note(int kind, int64_t pos, double q, const BandValue& v, const Band::Stop& st) {
    if (!on_) return;
    Slots& k = k_[kind];
    k.q[slot_][size_t(pos)] = q;
    k.f[slot_][size_t(pos)] = st.f;
    k.b[slot_][size_t(pos)] = int8_t(branch(v, st));
  }

  // The element's stiffness dF/dq for the re-solve at z: true with the
  // secant in *slope where it changed branch at the trial (now or earlier
  // in this Newton iteration), false to keep its tangent.
  bool secant(int kind, int64_t pos, double* slope);
  // The bytes held (MemoryTable).
  size_t bytes() const;

 private:
  struct Slots {
    std::vector<double> q[2], f[2];
    std::vector<int8_t> b[2];
    std::vector<uint32_t> mark;  // the Newton iteration (stamp_) it last changed branch in
  };
  Slots k_[3];
  bool on_ = false;
  int z_ = 0, slot_ = 0;
  uint32_t stamp_ = 1;
};

}  // namespace drape
