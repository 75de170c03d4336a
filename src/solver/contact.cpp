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

// In the (rho, z) half-plane the disc is a rectangle: the box's distance in
// two dimensions, q_r = rho - r along the radial direction e and q_z along z.
// Outside, d = |max(q, 0)| and n = (max(q_r, 0) e + max(q_z, 0) s_z z)/d;
// its Hessian is (P_r e e^T + P_z z z^T + max(q_r, 0) (I_xy - e e^T)/rho
// - n n^T)/d, P the indicators of q > 0 (e turns with x: de/dx = (I_xy -
// e e^T)/rho). Inside, the nearer of the rim (curved) and the faces (flat).
double disc_distance(const Obstacle& o, const double* x, double* n, double* hess) {
  const double rx = x[0] - o.center[0], ry = x[1] - o.center[1], rz = x[2] - o.center[2];
  const double rho = std::sqrt(rx * rx + ry * ry);
  const double e[3] = {rho > 0 ? rx / rho : 1.0, rho > 0 ? ry / rho : 0.0, 0.0};
  const double sz = rz >= 0 ? 1.0 : -1.0;
  const double qr = rho - o.radius, qz = std::fabs(rz) - o.half[2];
  if (hess) std::fill(hess, hess + 9, 0.0);
  if (qr <= 0 && qz <= 0) {  // inside
    // As for the box: a bottom standing on the floor is no way out.
    const bool on_floor = o.floor && o.center[2] - o.half[2] <= o.floor_z;
    const bool rim = qr > qz || (sz < 0 && on_floor);
    for (int k = 0; k < 3; ++k) n[k] = rim ? e[k] : (k == 2 ? sz : 0.0);
    if (hess && rim && rho > 0)  // the rim curves: n = e turns with x
      for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) hess[3 * i + j] = ((i == j) - e[i] * e[j]) / rho;
    return rim ? qr : qz;
  }
  const double a = std::max(qr, 0.0), b = std::max(qz, 0.0), d = std::sqrt(a * a + b * b);
  for (int k = 0; k < 3; ++k) n[k] = (a * e[k] + (k == 2 ? b * sz : 0.0)) / d;
  if (hess) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        double h = -n[i] * n[j];
        if (qr > 0) h += e[i] * e[j] + (i < 2 && j < 2 ? a * ((i == j) - e[i] * e[j]) / rho : 0.0);
        if (qz > 0 && i == 2 && j == 2) h += 1.0;
        hess[3 * i + j] = h / d;
      }
  }
  return d;
}

double shape_distance(const Obstacle& o, const double* x, double* n, double* hess) {
  if (o.shape == ObstacleShape::Box) return box_distance(o, x, n, hess);
  if (o.shape == ObstacleShape::Sphere) return sphere_distance(o, x, n, hess);
  if (o.shape == ObstacleShape::Disc) return disc_distance(o, x, n, hess);
  return 1e300;
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

bool contact_force(const Contact& c, const double* x, double* force, const double* r,
                   double* jac_t_r, double* slope) {
  force[0] = force[1] = force[2] = 0;
  bool hit = false;
  const Obstacle& o = c.obstacle;
  double n[3], hess_at[9];
  // The curvature term only enters -(dF/dx)^T r: the Newton passes, which do
  // not ask for it, skip its nine divisions per particle.
  double* hess = jac_t_r ? hess_at : nullptr;
  if (o.shape == ObstacleShape::Box && !beyond_layer(o, x, c.thickness)) {
    const double d = box_distance(o, x, n, hess);
    hit |= add_surface(c, d, n, hess, force, r, jac_t_r, slope);
  } else if (o.shape == ObstacleShape::Sphere || o.shape == ObstacleShape::Disc) {
    const double d = shape_distance(o, x, n, hess);
    hit |= add_surface(c, d, n, hess, force, r, jac_t_r, slope);
  }
  if (o.floor) {
    const double nz[3] = {0, 0, 1};
    hit |= add_surface(c, x[2] - o.floor_z, nz, nullptr, force, r, jac_t_r, slope);
  }
  return hit;
}

bool push_out(const Obstacle& o, double clearance, double* x) {
  bool moved = false;
  double n[3];
  const double d = shape_distance(o, x, n, nullptr);
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
  const double d = shape_distance(o, x, n, nullptr);
  if (d < 0) settle(d, n);
  const double up[3] = {0, 0, 1};
  if (o.floor && x[2] < o.floor_z) settle(x[2] - o.floor_z, up);
}

double clearance(const Obstacle& o, const double* x) {
  double n[3];
  const double d = shape_distance(o, x, n, nullptr);
  return o.floor ? std::min(d, x[2] - o.floor_z) : d;
}

double penetration(const Obstacle& o, const double* x) {
  return std::max(0.0, -clearance(o, x));
}

}  // namespace drape
