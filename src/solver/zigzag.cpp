#include "solver/zigzag.hpp"

#include <cmath>

namespace drape {

namespace {

// The turn of the mesh line through p along d: the change of its unit
// tangent, whose length is about the turning angle.
void line_turn(const Cloth& c, int64_t p, int d, double* out) {
  const double* x = c.x();
  const double *a = x + 3 * c.prev_at(d, p), *b = x + 3 * p, *n = x + 3 * c.next_at(d, p);
  double u[3], v[3], lu = 0, lv = 0;
  for (int k = 0; k < 3; ++k) {
    u[k] = b[k] - a[k];
    v[k] = n[k] - b[k];
    lu += u[k] * u[k];
    lv += v[k] * v[k];
  }
  lu = std::sqrt(lu);
  lv = std::sqrt(lv);
  for (int k = 0; k < 3; ++k) out[k] = (lu > 0 && lv > 0) ? v[k] / lv - u[k] / lu : 0.0;
}

}  // namespace

Zigzag count_zigzags(const Cloth& c, const std::vector<int64_t>& particles, const Reducer& red,
                     double min_turn) {
  Zigzag z;
  const double floor2 = min_turn * min_turn;
  for (int64_t p : particles)
    for (int d = 0; d < 2; ++d) {
      const int64_t q = c.next_at(d, p);
      if (!c.triple_on_at(2 * p + d) || q < 0 || !c.triple_on_at(2 * q + d)) continue;
      double s[3], t[3];
      line_turn(c, p, d, s);
      line_turn(c, q, d, t);
      const double ss = s[0] * s[0] + s[1] * s[1] + s[2] * s[2], tt = t[0] * t[0] + t[1] * t[1] + t[2] * t[2];
      const double st = s[0] * t[0] + s[1] * t[1] + s[2] * t[2];
      ++z.pairs;
      // Opposite senses: the two turns more than 120 degrees apart.
      if (ss > floor2 && tt > floor2 && st < -0.5 * std::sqrt(ss * tt)) ++z.zigzags;
    }
  z.pairs = red.sum_i64(z.pairs);
  z.zigzags = red.sum_i64(z.zigzags);
  return z;
}

}  // namespace drape
