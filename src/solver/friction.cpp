// Lagged Coulomb friction against the obstacle and the floor (contact.hpp).
// Freezing N and n at the step's start makes the friction a function of the
// particle's own position alone, with a symmetric Jacobian: Newton's K gets
// one more per-particle 3x3 block, and the term is as local as the
// penalty (the same on any ranks and threads).
#include <cmath>

#include "solver/contact.hpp"

namespace drape {

namespace {

// A surface holding the particle at the step's start: mu N and its normal.
struct Hold {
  double mu_n = 0;
  double n[3] = {0, 0, 0};
};

// The surfaces the particle at x1 touched (at most the shape and the floor).
int holds_at(const Contact& c, const double* x1, Hold* h) {
  const Obstacle& o = c.obstacle;
  int count = 0;
  auto hold = [&](double mu, double d, const double* n) {
    const double pen = c.thickness - d;
    if (mu <= 0 || pen <= 0) return;
    double slope;
    h[count].mu_n = mu * penalty(c, pen, &slope);
    for (int k = 0; k < 3; ++k) h[count].n[k] = n[k];
    ++count;
  };
  double n[3];
  // Every product and evaluation asks, for every particle: the far ones
  // are told apart without the distance.
  if (o.shape != ObstacleShape::None && c.friction > 0 && !beyond_layer(o, x1, c.thickness))
    hold(c.friction, shape_distance(o, x1, n, nullptr), n);
  if (o.floor) {
    const double up[3] = {0, 0, 1};
    hold(c.floor_friction, x1[2] - o.floor_z, up);
  }
  return count;
}

// The slip u across n since the step's start, and |u|.
double slip_of(const Hold& h, const double* x, const double* x1, double* u) {
  double d[3], dn = 0;
  for (int k = 0; k < 3; ++k) {
    d[k] = x[k] - x1[k];
    dn += d[k] * h.n[k];
  }
  double s2 = 0;
  for (int k = 0; k < 3; ++k) {
    u[k] = d[k] - dn * h.n[k];
    s2 += u[k] * u[k];
  }
  return std::sqrt(s2);
}

// The force is -mu N phi(s) u with phi = f(s)/s: 2/eps - s/eps^2 on the
// ramp, 1/s beyond; dphi/ds / s is what the u u^T part of the Jacobian needs.
double phi(double s, double eps) { return s < eps ? (2 - s / eps) / eps : 1 / s; }
double dphi_over_s(double s, double eps) { return s < eps ? -1 / (eps * eps * std::max(s, 1e-300)) : -1 / (s * s * s); }

// -dF/dx of one hold: mu N (phi (I - n n^T) + dphi/ds / s u u^T).
void add_block(const Hold& h, double s, const double* u, double eps, double* block) {
  const double a = h.mu_n * phi(s, eps), b = s > 0 ? h.mu_n * dphi_over_s(s, eps) : 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) block[3 * i + j] += a * ((i == j) - h.n[i] * h.n[j]) + b * u[i] * u[j];
}

}  // namespace

void friction_force(const Contact& c, const double* x, const double* x1, double* force, const double* r,
                    double* jac_t_r) {
  if (!c.has_friction()) return;
  Hold h[2];
  const int count = holds_at(c, x1, h);
  for (int k = 0; k < count; ++k) {
    double u[3];
    const double s = slip_of(h[k], x, x1, u);
    const double a = h[k].mu_n * phi(s, c.slip);
    for (int i = 0; i < 3; ++i) force[i] -= a * u[i];
    if (jac_t_r) {  // the block is symmetric: J^T r = J r
      double blk[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
      add_block(h[k], s, u, c.slip, blk);
      for (int i = 0; i < 3; ++i) jac_t_r[i] += blk[3 * i] * r[0] + blk[3 * i + 1] * r[1] + blk[3 * i + 2] * r[2];
    }
  }
}

bool friction_block(const Contact& c, const double* x, const double* x1, double* block) {
  if (!c.has_friction()) return false;
  Hold h[2];
  const int count = holds_at(c, x1, h);
  for (int k = 0; k < count; ++k) {
    double u[3];
    const double s = slip_of(h[k], x, x1, u);
    add_block(h[k], s, u, c.slip, block);
  }
  return count > 0;
}

double friction_trace(const Contact& c, const double* x, const double* x1, bool* held) {
  double blk[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  const bool holds = friction_block(c, x, x1, blk);
  if (held) *held = holds;
  return holds ? blk[0] + blk[4] + blk[8] : 0.0;
}

}  // namespace drape
