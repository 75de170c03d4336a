#include "solver/drape_coefficient.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace drape {

namespace {

// A square raster of covered pixels: origin (x0, y0), pixel side h.
struct Raster {
  int n = 0;
  double x0 = 0, y0 = 0, h = 0;
  std::vector<uint8_t> on;
  double centre_x(int i) const { return x0 + (i + 0.5) * h; }
  double centre_y(int j) const { return y0 + (j + 0.5) * h; }
  double area() const {
    int64_t count = 0;
    for (uint8_t v : on) count += v;
    return double(count) * h * h;
  }
};

double cross(double ax, double ay, double bx, double by, double px, double py) {
  return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

// Covers the pixels whose centres lie in triangle abc (either orientation,
// edges included), in xy.
void fill_triangle(Raster& r, const double* a, const double* b, const double* c) {
  const double lo_x = std::min({a[0], b[0], c[0]}), hi_x = std::max({a[0], b[0], c[0]});
  const double lo_y = std::min({a[1], b[1], c[1]}), hi_y = std::max({a[1], b[1], c[1]});
  const int i0 = std::max(0, int(std::floor((lo_x - r.x0) / r.h - 0.5)));
  const int i1 = std::min(r.n - 1, int(std::ceil((hi_x - r.x0) / r.h - 0.5)));
  const int j0 = std::max(0, int(std::floor((lo_y - r.y0) / r.h - 0.5)));
  const int j1 = std::min(r.n - 1, int(std::ceil((hi_y - r.y0) / r.h - 0.5)));
  for (int i = i0; i <= i1; ++i)
    for (int j = j0; j <= j1; ++j) {
      const double px = r.centre_x(i), py = r.centre_y(j);
      const double u = cross(a[0], a[1], b[0], b[1], px, py), v = cross(b[0], b[1], c[0], c[1], px, py),
                   w = cross(c[0], c[1], a[0], a[1], px, py);
      if ((u >= 0 && v >= 0 && w >= 0) || (u <= 0 && v <= 0 && w <= 0)) r.on[size_t(i) * r.n + j] = 1;
    }
}

// The cell of p, if any: p, its next particles a (along i) and b (along j),
// and d, next to both.
bool cell_of(const Cloth& c, int64_t p, int64_t& a, int64_t& b, int64_t& d) {
  if (!c.active(p)) return false;
  a = c.next_at(0, p), b = c.next_at(1, p);
  if (a < 0 || b < 0) return false;
  d = c.next_at(1, a);
  return d >= 0 && d == c.next_at(0, b);
}

// The specimen flat, where make_cloth laid it out.
void rest_position(const Cloth& c, const ClothSpec& s, int64_t p, double* x) {
  const Grid& g = c.grid;
  const int i = int(p / g.nj), j = int(p % g.nj);
  x[0] = s.center[0] + i * g.hi - 0.5 * s.size[0];
  x[1] = s.center[1] + j * g.hj - 0.5 * s.size[1];
  x[2] = 0;
}

// The cells of the particles of `tiles`, two triangles each: at positions x,
// or at rest (x null).
void fill_cells(Raster& r, const Cloth& c, const double* x, const ClothSpec& spec, const Tiling& tiling,
                const std::vector<int>& tiles) {
  double rest[4][3];
  for (int t : tiles) {
    const TileRange g = tiling.range(t);
    for (int i = g.i0; i < g.i1; ++i)
      for (int j = g.j0; j < g.j1; ++j) {
        const int64_t p = c.grid.id(i, j);
        int64_t corner[4];
        if (!cell_of(c, p, corner[1], corner[3], corner[2])) continue;
        corner[0] = p;
        const double* q[4];
        for (int k = 0; k < 4; ++k) {
          if (x) {
            q[k] = x + 3 * corner[k];
          } else {
            rest_position(c, spec, corner[k], rest[k]);
            q[k] = rest[k];
          }
        }
        fill_triangle(r, q[0], q[1], q[2]);
        fill_triangle(r, q[0], q[2], q[3]);
      }
  }
}

void fill_disc(Raster& r, const ObstacleSpec& o) {
  for (int i = 0; i < r.n; ++i)
    for (int j = 0; j < r.n; ++j) {
      const double dx = r.centre_x(i) - o.center[0], dy = r.centre_y(j) - o.center[1];
      if (dx * dx + dy * dy <= o.radius * o.radius) r.on[size_t(i) * r.n + j] = 1;
    }
}

// The shadow's outline radius about (cx, cy) at each whole degree: the last
// covered pixel along the ray, stepping half a pixel.
std::vector<double> outline(const Raster& r, double cx, double cy) {
  std::vector<double> out(360, 0.0);
  const double reach = 0.5 * r.n * r.h * std::sqrt(2.0);
  for (int k = 0; k < 360; ++k) {
    const double a = 2 * M_PI * k / 360, ux = std::cos(a), uy = std::sin(a);
    for (double t = 0; t <= reach; t += 0.5 * r.h) {
      const int i = int(std::floor((cx + t * ux - r.x0) / r.h)), j = int(std::floor((cy + t * uy - r.y0) / r.h));
      if (i < 0 || j < 0 || i >= r.n || j >= r.n) break;
      if (r.on[size_t(i) * r.n + j]) out[k] = t;
    }
  }
  return out;
}

// Rises from below mean - swing/6 to above mean + swing/6, once per node.
int count_nodes(const std::vector<double>& rad, double least_swing) {
  const auto [lo, hi] = std::minmax_element(rad.begin(), rad.end());
  if (*hi - *lo < least_swing) return 0;
  double mean = 0;
  for (double v : rad) mean += v;
  mean /= double(rad.size());
  const double up = mean + (*hi - mean) / 3, down = mean - (mean - *lo) / 3;
  // Start where the outline is low, so each rise is counted once around.
  const size_t start = size_t(lo - rad.begin());
  int nodes = 0;
  bool low = true;
  for (size_t k = 0; k <= rad.size(); ++k) {
    const double v = rad[(start + k) % rad.size()];
    if (low && v > up) {
      ++nodes;
      low = false;
    } else if (!low && v < down) {
      low = true;
    }
  }
  return nodes;
}

}  // namespace

bool is_drape_test(const Scene& s) {
  return s.cloth.shape == ClothShape::Disc && s.obstacle.shape == ObstacleShape::Disc;
}

namespace {

Raster drape_raster(const Scene& s, int pixels) {
  Raster r;
  r.n = pixels;
  const double reach = 1.1 * 0.5 * std::max(s.cloth.size[0], s.cloth.size[1]);
  r.h = 2 * reach / pixels;
  r.x0 = s.cloth.center[0] - reach;
  r.y0 = s.cloth.center[1] - reach;
  r.on.assign(size_t(pixels) * pixels, 0);
  return r;
}

}  // namespace

DrapeCover drape_cover(const Cloth& c, const double* x, const Scene& s, const Tiling& tiling,
                       const std::vector<int>& tiles, int pixels) {
  Raster r = drape_raster(s, pixels);
  DrapeCover cover;
  fill_cells(r, c, x, s.cloth, tiling, tiles);
  cover.shadow.swap(r.on);
  r.on.assign(cover.shadow.size(), 0);
  fill_cells(r, c, nullptr, s.cloth, tiling, tiles);
  cover.specimen.swap(r.on);
  return cover;
}

DrapeTest drape_figures(const Cloth& c, const Scene& s, DrapeCover& cover, int pixels) {
  Raster r = drape_raster(s, pixels);
  DrapeTest t;
  fill_disc(r, s.obstacle);
  t.disc = r.area();
  r.on.swap(cover.shadow);
  fill_disc(r, s.obstacle);
  t.shadow = r.area();
  // The cut's staircase alone swings the outline by up to about a spacing.
  const double least_swing = std::max(0.02 * 0.5 * s.cloth.size[0], 2 * std::max(c.grid.hi, c.grid.hj));
  t.nodes = count_nodes(outline(r, s.obstacle.center[0], s.obstacle.center[1]), least_swing);
  r.on.swap(cover.specimen);
  fill_disc(r, s.obstacle);
  t.specimen = r.area();
  t.coefficient = t.specimen > t.disc ? (t.shadow - t.disc) / (t.specimen - t.disc) : 0.0;
  return t;
}

DrapeTest drape_test(const Cloth& c, const double* x, const Scene& s, int pixels) {
  const Tiling whole(c.grid.ni, c.grid.nj, std::max(c.grid.ni, c.grid.nj));
  DrapeCover cover = drape_cover(c, x, s, whole, {0}, pixels);
  return drape_figures(c, s, cover, pixels);
}

}  // namespace drape
