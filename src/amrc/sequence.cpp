#include "amrc/sequence.hpp"

#include <algorithm>
#include <cmath>

#include "mesh/active_lists.hpp"
#include "mesh/topology.hpp"
#include "solver/cost.hpp"

namespace drape {

int sequence_start_level(const Grid& g, double spacing) {
  const double h = std::max(g.hi, g.hj);
  const int intervals = std::min(g.ni, g.nj) - 1;
  int level = 0;
  while (level < 10 && h * double(2 << level) <= spacing && (intervals >> (level + 1)) >= 8) ++level;
  return level;
}

int64_t uniform_level_particles(const Grid& g, int level) {
  const auto side = [level](int n) { return int64_t((n - 1 + (1 << level) - 1) >> level) + 1; };
  return side(g.ni) * side(g.nj);
}

double next_stage_seconds(StageTime last, StageTime before, bool multigrid_next) {
  const bool alike = before.multigrid == last.multigrid && last.multigrid == multigrid_next;
  const double growth = before.seconds > 0 && alike ? last.seconds / before.seconds : 0;
  return last.seconds * std::max(multigrid_next ? kMultigridStageGrowth : kJacobiStageGrowth, growth);
}

namespace {

// Eased edges keep this much strain: the tension of a cloth hanging under
// its weight (a fraction of that) stays as it was.
constexpr double kEasedStrain = 0.01;

// The edge's rest length in the material: its span on the finest grid.
double material_rest(const Cloth& c, int64_t s) { return edge_rest_geometry(c, s).rest; }

double length(const Cloth& c, int64_t s) {
  const double* x = c.x();
  const int64_t a = s >> 1, b = c.next_at(s & 1, a);
  double d2 = 0;
  for (int k = 0; k < 3; ++k) d2 += (x[3 * b + k] - x[3 * a + k]) * (x[3 * b + k] - x[3 * a + k]);
  return std::sqrt(d2);
}

}  // namespace

double ease_stretched_edges(const Cloth& c, Evaluator& ev) {
  double* rest_of = ev.edge_rest_lengths();
  const ActiveList& edges = ev.lists().edges;
  const ActiveList& ring = ev.lists().ring_edges;
  double worst = 0;
  for (const ActiveList* l : {&edges, &ring}) {
    const int64_t n = l->size(), base = l == &edges ? 0 : edges.size();
#pragma omp parallel for schedule(static) reduction(max : worst)
    for (int64_t k = 0; k < n; ++k) {
      const int64_t s = l->items[k];
      const double rest = material_rest(c, s), len = length(c, s);
      rest_of[base + k] = std::max(rest, len / (1 + kEasedStrain));
      worst = std::max(worst, len / rest - 1);
    }
  }
  return worst;
}

void relax_eased_edges(const Cloth& c, Evaluator& ev, double rate, double dt) {
  double* rest_of = ev.edge_rest_lengths();
  const ActiveList& edges = ev.lists().edges;
  const ActiveList& ring = ev.lists().ring_edges;
  for (const ActiveList* l : {&edges, &ring}) {
    const int64_t n = l->size(), base = l == &edges ? 0 : edges.size();
#pragma omp parallel for schedule(static)
    for (int64_t k = 0; k < n; ++k) {
      const double rest = material_rest(c, l->items[k]);
      rest_of[base + k] = std::max(rest, rest_of[base + k] - rate * dt * rest);
    }
  }
}

void eased_rest_by_slot(const Cloth& c, Evaluator& ev, double* by_slot) {
  const double* rest_of = ev.edge_rest_lengths();
  const ActiveList& edges = ev.lists().edges;
  for (int64_t k = 0; k < edges.size(); ++k) by_slot[c.pair_slot(edges.items[k])] = rest_of[k];
}

void restore_eased_edges(const Cloth& c, Evaluator& ev, const double* by_slot) {
  double* rest_of = ev.edge_rest_lengths();
  const ActiveList& edges = ev.lists().edges;
  const ActiveList& ring = ev.lists().ring_edges;
  for (const ActiveList* l : {&edges, &ring}) {
    const int64_t n = l->size(), base = l == &edges ? 0 : edges.size();
    for (int64_t k = 0; k < n; ++k) rest_of[base + k] = by_slot[c.pair_slot(l->items[k])];
  }
}

}  // namespace drape
