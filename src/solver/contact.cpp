#include "solver/contact.hpp"

#include <algorithm>
#include <cmath>

namespace drape {

double box_distance(const Obstacle& o, const double* x, double* n, double* hess) {
  double q[3], s[3];
  for (int k = 0; k < 3; ++k) {
    const double r = x[k] - o.center[k];
    s[k] = r >= 0 ? 1.0 : -1.0;
    q[k] = std::fabs(r) - o.half[k];
  }
  if (hess) std::fill(hess, hess + 9, 0.0);
  const double qmax = std::max({q[0], q[1], q[2]});
  if (qmax <= 0) {  // inside: nearest face decides, flat there
    // A bottom standing on the floor is no way out: out through it is into
    // the floor, which pushes back, and the particle would stay inside.
    const bool on_floor = o.floor && o.center[2] - o.half[2] <= o.floor_z;
    int k = 0;
    for (int a = 1; a < 3; ++a)
      if (q[a] > q[k] && !(a == 2 && s[2] < 0 && on_floor)) k = a;
    n[0] = n[1] = n[2] = 0;
    n[k] = s[k];
    return q[k];
  }
  double o3[3], d2 = 0;
  for (int k = 0; k < 3; ++k) {
    o3[k] = std::max(q[k], 0.0);
    d2 += o3[k] * o3[k];
  }
  const double d = std::sqrt(d2);
  for (int k = 0; k < 3; ++k) n[k] = s[k] * o3[k] / d;
  if (hess) {  // (D - n n^T)/d, D selecting the axes outside the slab
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        hess[3 * a + b] = ((a == b && q[a] > 0) ? 1.0 : 0.0) - n[a] * n[b];
    for (int k = 0; k < 9; ++k) hess[k] /= d;
  }
  return d;
}

double sphere_distance(const Obstacle& o, const double* x, double* n, double* hess) {
  double r[3], d2 = 0;
  for (int k = 0; k < 3; ++k) {
    r[k] = x[k] - o.center[k];
    d2 += r[k] * r[k];
  }
  const double len = std::sqrt(d2);
  for (int k = 0; k < 3; ++k) n[k] = len > 0 ? r[k] / len : (k == 2 ? 1.0 : 0.0);
  if (hess) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) hess[3 * a + b] = ((a == b) - n[a] * n[b]) / std::max(len, 1e-300);
  }
  return len - o.radius;
}

double penalty(const Contact& c, double pen, double* slope) {
  const double s = 0.5 * c.thickness, k = c.stiffness;
  *slope = pen < s ? k * pen / s : k;
  return pen < s ? k * pen * pen / (2 * s) : k * (pen - 0.5 * s);
}

namespace {

// Adds the penalty of one surface. The force grows quadratically over the
// first half of delta and linearly after, f(pen) = k pen^2/(2s) then
// k (pen - s/2): continuous with its slope, so the Newton residual is smooth
// and CG does not zig-zag at the onset of contact.
// -(dF/dx)^T r = f'(pen) n (n.r) - f(pen) H r.
bool add_surface(const Contact& c, double d, const double* n, const double* hess, double* force,
                 const double* r, double* jtr, double* slope) {
  const double pen = c.thickness - d;
  if (pen <= 0) return false;
  double df;
  const double f = penalty(c, pen, &df);
  for (int i = 0; i < 3; ++i) force[i] += f * n[i];
  if (slope) *slope += df;
  if (jtr) {
    const double nr = n[0] * r[0] + n[1] * r[1] + n[2] * r[2];
    for (int a = 0; a < 3; ++a) {
      double hr = 0;
      if (hess)
        for (int b = 0; b < 3; ++b) hr += hess[3 * a + b] * r[b];
      jtr[a] += df * n[a] * nr - f * hr;
    }
  }
  return true;
}

}  // namespace

namespace {
// Whether x lies beyond the layer off one of the box's faces: its distance
// is then at least that face's gap (sqrt(fl(q^2)) is q exactly and further
// terms only add), so the penalty is zero and box_distance's square root and
// divisions need not run: the same result, most of the cloth away from the box.
inline bool beyond_box_layer(const Obstacle& o, const double* x, double layer) {
  for (int k = 0; k < 3; ++k) {
    const double q = std::fabs(x[k] - o.center[k]) - o.half[k];
    if (q > 0 && q >= layer) return true;
  }
  return false;
}
}  // namespace

bool contact_force(const Contact& c, const double* x, double* force, const double* r,
                   double* jac_t_r, double* slope) {
  force[0] = force[1] = force[2] = 0;
  bool hit = false;
  const Obstacle& o = c.obstacle;
  double n[3], hess_at[9];
  // The curvature term only enters -(dF/dx)^T r: the Newton passes, which do
  // not ask for it, skip its nine divisions per particle.
  double* hess = jac_t_r ? hess_at : nullptr;
  if (o.shape == ObstacleShape::Box && !beyond_box_layer(o, x, c.thickness)) {
    const double d = box_distance(o, x, n, hess);
    hit |= add_surface(c, d, n, hess, force, r, jac_t_r, slope);
  } else if (o.shape == ObstacleShape::Sphere) {
    const double d = sphere_distance(o, x, n, hess);
    hit |= add_surface(c, d, n, hess, force, r, jac_t_r, slope);
  }
  if (o.floor) {
    const double nz[3] = {0, 0, 1};
    hit |= add_surface(c, x[2] - o.floor_z, nz, nullptr, force, r, jac_t_r, slope);
  }
  return hit;
}

namespace {
// Signed distance to the box or sphere and its outward normal n; far (1e300) without one.
double shape_distance(const Obstacle& o, const double* x, double* n) {
  if (o.shape == ObstacleShape::Box) return box_distance(o, x, n, nullptr);
  if (o.shape == ObstacleShape::Sphere) return sphere_distance(o, x, n, nullptr);
  return 1e300;
}
}  // namespace

bool push_out(const Obstacle& o, double clearance, double* x) {
  bool moved = false;
  double n[3];
  const double d = shape_distance(o, x, n);
  if (d < clearance) {
    for (int k = 0; k < 3; ++k) x[k] += (clearance - d) * n[k];
    moved = true;
  }
  if (o.floor && x[2] < o.floor_z + clearance) {
    x[2] = o.floor_z + clearance;
    moved = true;
  }
  return moved;
}

void settle_on_surface(const Obstacle& o, double* x, double* dx) {
  auto settle = [&](double d, const double* n) {  // inside by -d along the outward normal n
    for (int k = 0; k < 3; ++k) x[k] -= d * n[k];
    const double into = dx[0] * n[0] + dx[1] * n[1] + dx[2] * n[2];
    if (into < 0)
      for (int k = 0; k < 3; ++k) dx[k] -= into * n[k];
  };
  double n[3];
  const double d = shape_distance(o, x, n);
  if (d < 0) settle(d, n);
  const double up[3] = {0, 0, 1};
  if (o.floor && x[2] < o.floor_z) settle(x[2] - o.floor_z, up);
}

double clearance(const Obstacle& o, const double* x) {
  double n[3];
  const double d = shape_distance(o, x, n);
  return o.floor ? std::min(d, x[2] - o.floor_z) : d;
}

double penetration(const Obstacle& o, const double* x) {
  return std::max(0.0, -clearance(o, x));
}

}  // namespace drape
