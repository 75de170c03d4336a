#include "solver/band_active_set.hpp"

#include "solver/cost.hpp"
#include "solver/fit.hpp"

namespace drape {

void BandActiveSet::enable(bool on) {
  on_ = on;
  if (on) return;
  for (Slots& k : k_) {
    for (int s = 0; s < 2; ++s) {
      std::vector<double>().swap(k.q[s]);
      std::vector<double>().swap(k.f[s]);
      std::vector<int8_t>().swap(k.b[s]);
    }
    std::vector<uint32_t>().swap(k.mark);
  }
}

void BandActiveSet::fit(int kind, size_t count, size_t most, bool exact) {
  if (!on_) return;
  Slots& k = k_[kind];
  for (int s = 0; s < 2; ++s) {
    drape::fit(k.q[s], count, most, exact, 0.0);
    drape::fit(k.f[s], count, most, exact, 0.0);
    drape::fit(k.b[s], count, most, exact, int8_t(0));
  }
  drape::fit(k.mark, count, most, exact, uint32_t(0));
}

bool BandActiveSet::secant(int kind, int64_t pos, double* slope) {
  Slots& k = k_[kind];
  const size_t i = size_t(pos);
  const int z = z_, t = 1 - z_;
  if (k.b[z][i] != k.b[t][i]) k.mark[i] = stamp_;
  if (k.mark[i] != stamp_) return false;
  const double dq = k.q[t][i] - k.q[z][i];
  if (!(dq != 0)) return false;  // no strain change: its tangent is all there is
  *slope = (k.f[t][i] - k.f[z][i]) / dq;
  return true;
}

size_t BandActiveSet::bytes() const {
  size_t b = 0;
  for (const Slots& k : k_) {
    for (int s = 0; s < 2; ++s)
      b += (k.q[s].capacity() + k.f[s].capacity()) * sizeof(double) + k.b[s].capacity() * sizeof(int8_t);
    b += k.mark.capacity() * sizeof(uint32_t);
  }
  return b;
}

void Evaluator::track_branches(bool on) {
  active_.enable(on);
  fit_arrays(true);
}

// The kept numbers carry the band's slope: an edge's over its rest length,
// a triple's times its width over its rest length, a cell's times its area.
// Each element by its own position: the same on every thread count and on
// every rank that holds it (the ring's too).
int64_t Evaluator::kink_tangents() {
  if (!active_.enabled() || !keep_ || !settled_) return 0;
  int64_t changed = 0;
  double s;
  const int64_t ne = lists_.edges.size() + lists_.ring_edges.size();
  for (int64_t pos = 0; pos < ne; ++pos)
    if (active_.secant(0, pos, &s)) {
      kg_e_[kKgEdge * pos + 1] = s / rest_e_[pos];
      ++changed;
    }
  const int64_t nt = lists_.triples.size() + lists_.ring_triples.size();
  for (int64_t pos = 0; pos < nt; ++pos)
    if (active_.secant(1, pos, &s)) {
      kg_t_[kKgTriple * pos] = width_t_[pos] * s / triple_rest(slot_at(lists_.triples, lists_.ring_triples, pos), pos);
      ++changed;
    }
  const int64_t ns = lists_.shears.size() + lists_.ring_shears.size();
  for (int64_t pos = 0; pos < ns; ++pos)
    if (active_.secant(2, pos, &s)) {
      kg_s_[kKgCell * pos] = cell_area_at(slot_at(lists_.shears, lists_.ring_shears, pos), pos) * s;
      ++changed;
    }
  return changed;
}

}  // namespace drape
