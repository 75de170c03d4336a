#pragma once
// A bytes model of the evaluator's kernels: the memory traffic each must
// move at the least, counted like STREAM (each array entry read or written
// once per pass, no write-allocate), so that bytes / seconds compares with a
// STREAM triad's bandwidth. Per element and particle, from the arrays its
// pass reads and writes (cost.cpp, stiffness.cpp); a particle's positions
// (or residuals, or the product's operand) are counted once per element
// pass that reads them, its neighbours' being in cache by then.
#include <cstdint>

#include "mesh/active_lists.hpp"
#include "mesh/cloth.hpp"

namespace drape {

struct TrafficCounts {
  int64_t particles = 0, edges = 0, triples = 0, cells = 0, grid = 0;
};

inline TrafficCounts traffic_counts(const ActiveLists& l, const Cloth& c) {
  return {l.particles.size(), l.edges.size() + l.ring_edges.size(), l.triples.size() + l.ring_triples.size(),
          l.shears.size() + l.ring_shears.size(), c.grid.n()};
}

struct KernelBytes {
  // Bytes per element (edge, triple, cell) and per particle, and per grid
  // particle (whole-array passes such as clearing the gradient).
  double edge, triple, cell, particle, grid;
  double total(const TrafficCounts& n) const {
    return edge * double(n.edges) + triple * double(n.triples) + cell * double(n.cells) +
           particle * double(n.particles) + grid * double(n.grid);
  }
};

namespace traffic {
constexpr double kD = 8, kI32 = 4, kI64 = 8;
// An element's buffer entry (written by its pass, read by its particles' gather).
constexpr double kEdgeBuf = 3 * kD, kTripleBuf = 9 * kD, kCellBuf = 12 * kD;
}  // namespace traffic

// evaluate(z, nullptr): the element forces and band costs, each particle's
// residual, the cost sums.
inline KernelBytes cost_bytes() {
  using namespace traffic;
  // list item, neighbour ids, rest and width/area, anchor, force; buffer,
  // cost, slope, force derivative out; gathered once; summed once.
  const double edge = kI64 + kI32 + 2 * kD + kD + kD + kEdgeBuf + 3 * kD + kEdgeBuf + kD;
  const double triple = kI64 + 2 * kI32 + 3 * kD + 2 * kD + kD + kD + kTripleBuf + 3 * kD + kTripleBuf + kD;
  const double cell = kI64 + 3 * kI32 + 2 * kD + kD + kD + kCellBuf + 3 * kD + kCellBuf + kD;
  // item, gather row, x1, x2, mass; residual and cost out; cost summed;
  // positions read by the three element passes and this one.
  const double particle = kI64 + 64 + 3 * kD + 3 * kD + kD + 3 * kD + kD + kD + 4 * 3 * kD;
  return {edge, triple, cell, particle, 0};
}

// evaluate(z, grad): the cost, then the element gradient passes and the
// particles' gathers.
inline KernelBytes cost_gradient_bytes() {
  using namespace traffic;
  const KernelBytes c = cost_bytes();
  // item, neighbour ids, width/area (and a triple's axis), force, slope and
  // force derivative; buffer and the force's gradient out; gathered once.
  const double edge = kI64 + kI32 + kD + kD + 2 * kD + kEdgeBuf + kD + kEdgeBuf;
  const double triple = kI64 + 2 * kI32 + 3 * kD + kD + kD + 2 * kD + kTripleBuf + kD + kTripleBuf;
  const double cell = kI64 + 3 * kI32 + kD + kD + 2 * kD + kCellBuf + kD + kCellBuf;
  // item, row, residual, position, mass; gradient out; positions, residuals
  // and flags once per element pass.
  const double particle = kI64 + 64 + 3 * kD + 3 * kD + kD + 3 * kD + 3 * (6 * kD + 1);
  // The gradient cleared (8 unknowns a grid particle).
  return {c.edge + edge, c.triple + triple, c.cell + cell, c.particle + particle, 8 * kD};
}

// stiffness_product with its numbers kept (kg_e_, kg_t_, kg_s_) and wide
// buffers (BM_Kernels' evaluator, which took a gradient first): each
// element's particles' local indices (lo_e_, lo_t_, lo_s_); an edge's ends'
// grid ids and positions too (its direction and length are computed), and
// each particle's position (its contact terms).
inline KernelBytes product_bytes() {
  using namespace traffic;
  // item, local indices and neighbour, frozen tension and slope, width;
  // buffer out; gathered once.
  const double edge = kI64 + 2 * kI32 + kI32 + 2 * kD + kD + kEdgeBuf + kEdgeBuf;
  const double triple = kI64 + 3 * kI32 + 7 * kD + kTripleBuf + kTripleBuf;
  const double cell = kI64 + 4 * kI32 + 13 * kD + kCellBuf + kCellBuf;
  // item, row, mass, operand; result out; the operand once per element
  // pass; positions read by the edges' pass and this one.
  const double particle = kI64 + 64 + kD + 3 * kD + 3 * kD + 3 * 3 * kD + 2 * 3 * kD;
  return {edge, triple, cell, particle, 0};
}

}  // namespace drape
