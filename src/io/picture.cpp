// render_picture: a small software rasterizer for DIR/drape.png.
//
// Perspective camera at 35 degrees elevation, 30 degrees azimuth, framed on
// the cloth and the obstacle; z-buffered triangles with per-pixel normals,
// Lambert light from the camera side plus ambient, both cloth sides lit; the
// cloth coloured by height (viridis-like), a grey obstacle, and a chequered
// floor with a soft contact shadow. Rendered at 2x2 supersampling, written
// as an RGB PNG (chunks and CRCs here, deflate by zlib).
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/atomic_file.hpp"
#include "io/output.hpp"
#include "io/picture.hpp"
#include "mesh/cloth.hpp"

namespace drape {
namespace {

// ------------------------------------------------------------ vectors --

constexpr double kPi = 3.14159265358979323846;

struct V3 {
  double x = 0, y = 0, z = 0;
};
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
V3 normalized(V3 a) {
  const double n = std::sqrt(dot(a, a));
  return n > 0 ? (1.0 / n) * a : V3{0, 0, 1};
}

struct Rgb {
  float r = 0, g = 0, b = 0;
};
Rgb mix(Rgb a, Rgb b, double t) {
  const float s = float(t);
  return {a.r + (b.r - a.r) * s, a.g + (b.g - a.g) * s, a.b + (b.b - a.b) * s};
}
Rgb scale(Rgb a, double s) { return {float(a.r * s), float(a.g * s), float(a.b * s)}; }

// Height colours: five stops along viridis, linear in between.
Rgb height_colour(double t) {
  static const Rgb stops[5] = {{0.267f, 0.005f, 0.329f},
                               {0.231f, 0.322f, 0.545f},
                               {0.129f, 0.569f, 0.549f},
                               {0.369f, 0.788f, 0.384f},
                               {0.992f, 0.906f, 0.145f}};
  t = std::clamp(t, 0.0, 1.0) * 4.0;
  const int k = std::min(int(t), 3);
  return mix(stops[k], stops[k + 1], t - k);
}

// ------------------------------------------------------------- geometry --

// A triangle soup with per-vertex normals and colours.
struct Mesh {
  std::vector<V3> p, n;
  std::vector<Rgb> c;
  std::vector<std::array<int, 3>> tri;
  int add(V3 pos, V3 nor, Rgb col) {
    p.push_back(pos);
    n.push_back(nor);
    c.push_back(col);
    return int(p.size()) - 1;
  }
  void quad(int a, int b, int c2, int d) {
    tri.push_back({a, b, c2});
    tri.push_back({a, c2, d});
  }
};

struct Box3 {
  V3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  void add(V3 q) {
    lo = {std::min(lo.x, q.x), std::min(lo.y, q.y), std::min(lo.z, q.z)};
    hi = {std::max(hi.x, q.x), std::max(hi.y, q.y), std::max(hi.z, q.z)};
  }
  bool empty() const { return lo.x > hi.x; }
  std::array<V3, 8> corners() const {
    std::array<V3, 8> c;
    for (int k = 0; k < 8; ++k) c[k] = {k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z};
    return c;
  }
};

// Positions usable for drawing. Under AMRC, inactive particles lie inside
// coarse cells; they are filled by linear interpolation along grid lines
// (rows first, then columns), which spans each coarse cell with a smooth
// surface. A particle no active one brackets stays invalid.
struct Surface {
  int ni, nj;
  std::vector<V3> x;
  std::vector<uint8_t> ok;
};

void fill_line(Surface& s, int64_t first, int64_t stride, int len) {
  int last = -1;
  for (int k = 0; k < len; ++k) {
    if (!s.ok[first + k * stride]) continue;
    if (last >= 0 && k - last > 1) {
      const V3 a = s.x[first + last * stride], b = s.x[first + k * stride];
      for (int m = last + 1; m < k; ++m) {
        s.x[first + m * stride] = a + (double(m - last) / (k - last)) * (b - a);
        s.ok[first + m * stride] = 1;
      }
    }
    last = k;
  }
}

Surface make_surface(const FrameView& f) {
  Surface s{f.ni, f.nj, std::vector<V3>(size_t(f.ni) * f.nj), std::vector<uint8_t>(size_t(f.ni) * f.nj)};
  bool all = true;
  for (size_t p = 0; p < s.x.size(); ++p) {
    s.x[p] = {f.x[3 * p], f.x[3 * p + 1], f.x[3 * p + 2]};
    const bool finite = std::isfinite(s.x[p].x) && std::isfinite(s.x[p].y) && std::isfinite(s.x[p].z);
    s.ok[p] = finite && (!f.flags || (f.flags[p] & kActive));
    all = all && s.ok[p];
  }
  if (all) return s;
  for (int i = 0; i < s.ni; ++i) fill_line(s, int64_t(i) * s.nj, 1, s.nj);
  for (int j = 0; j < s.nj; ++j) fill_line(s, j, s.nj, s.ni);
  return s;
}

V3 point(const PictureSurface& s, size_t k) { return {s.x[3 * k], s.x[3 * k + 1], s.x[3 * k + 2]}; }

// The cloth's samples, coloured by height; smooth normals from the grid.
Mesh cloth_mesh(const PictureSurface& s, Box3& bounds) {
  const int mi = s.mi, mj = s.mj;
  auto at = [&](int a, int b) { return size_t(a) * mj + b; };
  Box3 own;
  for (int a = 0; a < mi; ++a)
    for (int b = 0; b < mj; ++b)
      if (s.ok[at(a, b)]) own.add(point(s, at(a, b)));
  if (own.empty()) return {};
  bounds.add(own.lo);
  bounds.add(own.hi);
  // A nearly flat cloth keeps a nearly uniform colour: the colour range is
  // at least a quarter of the cloth's width, centred on its heights.
  const double width = std::max(own.hi.x - own.lo.x, own.hi.y - own.lo.y);
  const double grow = std::max(0.0, 0.25 * width - (own.hi.z - own.lo.z)) / 2;
  const double zlo = own.lo.z - grow, zhi = own.hi.z + grow;
  Mesh m;
  std::vector<int> vid(size_t(mi) * mj, -1);
  auto pos = [&](int a, int b, int fa, int fb) {  // neighbour, or self where missing
    const int a2 = std::clamp(a, 0, mi - 1), b2 = std::clamp(b, 0, mj - 1);
    return s.ok[at(a2, b2)] ? point(s, at(a2, b2)) : point(s, at(fa, fb));
  };
  for (int a = 0; a < mi; ++a)
    for (int b = 0; b < mj; ++b) {
      if (!s.ok[at(a, b)]) continue;
      const V3 du = pos(a + 1, b, a, b) - pos(a - 1, b, a, b);
      const V3 dv = pos(a, b + 1, a, b) - pos(a, b - 1, a, b);
      const V3 q = point(s, at(a, b));
      const double t = zhi - zlo > 1e-12 ? (q.z - zlo) / (zhi - zlo) : 0.5;
      vid[size_t(a) * mj + b] = m.add(q, normalized(cross(du, dv)), height_colour(t));
    }
  for (int a = 0; a + 1 < mi; ++a)
    for (int b = 0; b + 1 < mj; ++b) {
      const int v00 = vid[size_t(a) * mj + b], v10 = vid[size_t(a + 1) * mj + b];
      const int v11 = vid[size_t(a + 1) * mj + b + 1], v01 = vid[size_t(a) * mj + b + 1];
      if (v00 >= 0 && v10 >= 0 && v11 >= 0 && v01 >= 0) m.quad(v00, v10, v11, v01);
    }
  return m;
}

const Rgb kObstacleColour{0.72f, 0.72f, 0.74f};

void add_box(Mesh& m, const ObstacleSpec& ob, Box3& bounds) {
  const V3 c{ob.center[0], ob.center[1], ob.center[2]};
  const V3 h{ob.size[0] / 2, ob.size[1] / 2, ob.size[2] / 2};
  // Each face: its normal axis and sign; corners walk the other two axes.
  for (int axis = 0; axis < 3; ++axis)
    for (int sign = -1; sign <= 1; sign += 2) {
      double nrm[3] = {0, 0, 0};
      nrm[axis] = sign;
      const V3 n{nrm[0], nrm[1], nrm[2]};
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      int ids[4];
      const int su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
      for (int k = 0; k < 4; ++k) {
        double d[3];
        d[axis] = sign;
        d[u] = su[k];
        d[v] = sv[k];
        const V3 q = c + V3{d[0] * h.x, d[1] * h.y, d[2] * h.z};
        bounds.add(q);
        ids[k] = m.add(q, n, kObstacleColour);
      }
      m.quad(ids[0], ids[1], ids[2], ids[3]);
    }
}

void add_sphere(Mesh& m, const ObstacleSpec& ob, Box3& bounds) {
  const V3 c{ob.center[0], ob.center[1], ob.center[2]};
  const int nlat = 32, nlon = 64;
  const int base = int(m.p.size());
  for (int a = 0; a <= nlat; ++a)
    for (int b = 0; b <= nlon; ++b) {
      const double th = kPi * a / nlat, ph = 2 * kPi * b / nlon;
      const V3 n{std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
      m.add(c + ob.radius * n, n, kObstacleColour);
    }
  for (int a = 0; a < nlat; ++a)
    for (int b = 0; b < nlon; ++b) {
      const int v = base + a * (nlon + 1) + b;
      m.quad(v, v + nlon + 1, v + nlon + 2, v + 1);
    }
  bounds.add(c - V3{ob.radius, ob.radius, ob.radius});
  bounds.add(c + V3{ob.radius, ob.radius, ob.radius});
}

// A vertical cylinder: its rim as quads, top and bottom as fans of quads.
void add_disc(Mesh& m, const ObstacleSpec& ob, Box3& bounds) {
  const V3 c{ob.center[0], ob.center[1], ob.center[2]};
  const double hz = ob.size[2] / 2;
  const int nseg = 96;
  for (int k = 0; k < nseg; ++k) {
    const double a0 = 2 * kPi * k / nseg, a1 = 2 * kPi * (k + 1) / nseg;
    const V3 e0{std::cos(a0), std::sin(a0), 0}, e1{std::cos(a1), std::sin(a1), 0};
    const V3 up{0, 0, hz}, top{0, 0, 1}, bottom{0, 0, -1};
    const int r00 = m.add(c + ob.radius * e0 - up, e0, kObstacleColour), r01 = m.add(c + ob.radius * e1 - up, e1, kObstacleColour);
    const int r11 = m.add(c + ob.radius * e1 + up, e1, kObstacleColour), r10 = m.add(c + ob.radius * e0 + up, e0, kObstacleColour);
    m.quad(r00, r01, r11, r10);
    for (const V3& n : {top, bottom}) {
      const V3 lid = n.z > 0 ? up : -1.0 * up;
      const int a = m.add(c + lid, n, kObstacleColour), b = m.add(c + lid + ob.radius * e0, n, kObstacleColour);
      const int d = m.add(c + lid + ob.radius * e1, n, kObstacleColour);
      m.tri.push_back({a, b, d});
    }
  }
  bounds.add(c - V3{ob.radius, ob.radius, hz});
  bounds.add(c + V3{ob.radius, ob.radius, hz});
}

// Indices 0, k, 2k, ... and the last one: at most ~max_points per side.
std::vector<int> sample(int n, int max_points) {
  const int step = std::max(1, (n - 1 + max_points - 2) / (max_points - 1));
  std::vector<int> idx;
  for (int k = 0; k < n - 1; k += step) idx.push_back(k);
  idx.push_back(n - 1);
  return idx;
}

constexpr int kSamples = 400;  // at most about this many grid lines each way

// The last active column <= j and the next >= j of row i at each sampled
// column (-1: none), from one sweep each way along the row.
void row_brackets(const uint8_t* flags, int nj, int i, const std::vector<int>& cols, std::vector<int>& scratch,
                  int32_t* left, int32_t* right) {
  const uint8_t* row = flags + int64_t(i) * nj;
  int last = -1;
  for (int j = 0; j < nj; ++j) scratch[j] = last = (row[j] & kActive) ? j : last;
  for (size_t b = 0; b < cols.size(); ++b) left[b] = scratch[cols[b]];
  last = -1;
  for (int j = nj - 1; j >= 0; --j) scratch[j] = last = (row[j] & kActive) ? j : last;
  for (size_t b = 0; b < cols.size(); ++b) right[b] = scratch[cols[b]];
}

// fill_line's interpolation, for the same operands in the same order.
V3 between(V3 a, V3 b, int m, int last, int k) { return a + (double(m - last) / (k - last)) * (b - a); }

}  // namespace

PicturePlan plan_picture(int ni, int nj, const uint8_t* flags) {
  PicturePlan plan;
  plan.ni = ni;
  plan.nj = nj;
  plan.rows = sample(ni, kSamples);
  plan.cols = sample(nj, kSamples);
  const int mi = int(plan.rows.size()), mj = int(plan.cols.size());
  // Rows first: every row's brackets at the sampled columns.
  std::vector<int32_t> left(size_t(ni) * mj), right(size_t(ni) * mj);
  std::vector<int> scratch(nj);
  for (int i = 0; i < ni; ++i) row_brackets(flags, nj, i, plan.cols, scratch, &left[size_t(i) * mj], &right[size_t(i) * mj]);
  auto row_ok = [&](int i, int b) { return left[size_t(i) * mj + b] >= 0 && right[size_t(i) * mj + b] >= 0; };
  // Then columns: the nearest rows with a value above and below each sample.
  plan.source.resize(size_t(mi) * mj);
  std::vector<int> up(ni), down(ni);
  for (int b = 0; b < mj; ++b) {
    int last = -1;
    for (int i = 0; i < ni; ++i) up[i] = last = row_ok(i, b) ? i : last;
    last = -1;
    for (int i = ni - 1; i >= 0; --i) down[i] = last = row_ok(i, b) ? i : last;
    for (int a = 0; a < mi; ++a) {
      PictureSource& src = plan.source[size_t(a) * mj + b];
      const int i = plan.rows[a];
      if (up[i] < 0 || down[i] < 0) continue;
      src.il = up[i];
      src.ir = down[i];
      const int ends[2] = {src.il, src.ir};
      for (int e = 0; e < 2; ++e) {
        src.jl[e] = left[size_t(ends[e]) * mj + b];
        src.jr[e] = right[size_t(ends[e]) * mj + b];
        plan.needed.push_back(int64_t(ends[e]) * nj + src.jl[e]);
        plan.needed.push_back(int64_t(ends[e]) * nj + src.jr[e]);
      }
    }
  }
  std::sort(plan.needed.begin(), plan.needed.end());
  plan.needed.erase(std::unique(plan.needed.begin(), plan.needed.end()), plan.needed.end());
  return plan;
}

PictureSurface picture_surface(const PicturePlan& plan, const double* values) {
  const int mi = int(plan.rows.size()), mj = int(plan.cols.size());
  PictureSurface s{mi, mj, std::vector<double>(3 * size_t(mi) * mj), std::vector<uint8_t>(size_t(mi) * mj)};
  auto x = [&](int i, int j) {
    const int64_t p = int64_t(i) * plan.nj + j;
    const size_t k = size_t(std::lower_bound(plan.needed.begin(), plan.needed.end(), p) - plan.needed.begin());
    return V3{values[3 * k], values[3 * k + 1], values[3 * k + 2]};
  };
  auto row_value = [&](int i, int jl, int jr, int j) {
    return jl == jr ? x(i, jl) : between(x(i, jl), x(i, jr), j, jl, jr);
  };
  for (int a = 0; a < mi; ++a)
    for (int b = 0; b < mj; ++b) {
      const size_t k = size_t(a) * mj + b;
      const PictureSource& src = plan.source[k];
      if (src.il < 0) continue;
      const int i = plan.rows[a], j = plan.cols[b];
      const V3 top = row_value(src.il, src.jl[0], src.jr[0], j);
      const V3 q = src.il == src.ir ? top : between(top, row_value(src.ir, src.jl[1], src.jr[1], j), i, src.il, src.ir);
      s.x[3 * k] = q.x, s.x[3 * k + 1] = q.y, s.x[3 * k + 2] = q.z;
      s.ok[k] = 1;
    }
  return s;
}

PictureSurface picture_surface(const FrameView& f) {
  const Surface full = make_surface(f);
  const std::vector<int> rows = sample(f.ni, kSamples), cols = sample(f.nj, kSamples);
  const int mi = int(rows.size()), mj = int(cols.size());
  PictureSurface s{mi, mj, std::vector<double>(3 * size_t(mi) * mj), std::vector<uint8_t>(size_t(mi) * mj)};
  for (int a = 0; a < mi; ++a)
    for (int b = 0; b < mj; ++b) {
      const size_t k = size_t(a) * mj + b, p = size_t(rows[a]) * f.nj + cols[b];
      if (!full.ok[p]) continue;  // undrawn samples hold zeros, as from a plan
      s.x[3 * k] = full.x[p].x, s.x[3 * k + 1] = full.x[p].y, s.x[3 * k + 2] = full.x[p].z;
      s.ok[k] = 1;
    }
  return s;
}

namespace {

// --------------------------------------------------------------- camera --

struct Camera {
  V3 eye, right, up, fwd;
  double focal = 1, cx = 0, cy = 0;
  double near = 1e-6;
  // Pixel coordinates and depth along the view axis.
  bool project(V3 q, double& sx, double& sy, double& depth) const {
    const V3 d = q - eye;
    depth = dot(d, fwd);
    if (depth < near) return false;
    sx = cx + focal * dot(d, right) / depth;
    sy = cy - focal * dot(d, up) / depth;
    return true;
  }
};

// Sets the camera so that `fit` fills most of the image: distance by
// bisection on the projected extent, then the image centre on the extent's.
Camera frame_camera(const Box3& fit, int w, int h) {
  const double el = 35 * kPi / 180, az = 30 * kPi / 180, vfov = 30 * kPi / 180;
  const V3 to_eye{std::cos(el) * std::sin(az), -std::cos(el) * std::cos(az), std::sin(el)};
  const V3 target = 0.5 * (fit.lo + fit.hi);
  const double radius = std::max(1e-6, 0.5 * std::sqrt(dot(fit.hi - fit.lo, fit.hi - fit.lo)));
  Camera cam;
  cam.fwd = -1.0 * to_eye;
  cam.right = normalized(cross(cam.fwd, V3{0, 0, 1}));
  cam.up = cross(cam.right, cam.fwd);
  cam.focal = 0.5 * h / std::tan(vfov / 2);
  cam.cx = 0.5 * w;
  cam.cy = 0.5 * h;
  const auto corners = fit.corners();
  auto extent = [&](double dist, double& x0, double& x1, double& y0, double& y1) {
    cam.eye = target + dist * to_eye;
    x0 = y0 = 1e300;
    x1 = y1 = -1e300;
    for (const V3& q : corners) {
      double sx, sy, d;
      if (!cam.project(q, sx, sy, d)) return false;
      x0 = std::min(x0, sx), x1 = std::max(x1, sx), y0 = std::min(y0, sy), y1 = std::max(y1, sy);
    }
    return true;
  };
  double lo = radius * 1e-3, hi = radius * 1e3;
  for (int it = 0; it < 60; ++it) {
    const double mid = std::sqrt(lo * hi);
    double x0, x1, y0, y1;
    const bool fits = extent(mid, x0, x1, y0, y1) && x1 - x0 <= 0.9 * w && y1 - y0 <= 0.88 * h;
    (fits ? hi : lo) = mid;
  }
  double x0, x1, y0, y1;
  extent(hi, x0, x1, y0, y1);
  cam.cx += 0.5 * w - 0.5 * (x0 + x1);
  cam.cy += 0.5 * h - 0.5 * (y0 + y1);
  cam.near = 1e-3 * hi;
  return cam;
}

// --------------------------------------------------------------- raster --

struct Light {
  V3 dir;          // towards the light
  V3 view;         // towards the camera
  double ambient = 0.3, diffuse = 0.75;
  // Lambert, both sides: the normal is turned to face the viewer first.
  double operator()(V3 n) const {
    if (dot(n, view) < 0) n = -1.0 * n;
    return ambient + diffuse * std::max(0.0, dot(n, dir));
  }
};

// A strip of the supersampled picture: rows y0 to y0 + h - 1 of `full`
// rows, each w pixels. Drawn a strip at a time, so that the picture's
// floats never span the whole picture; a pixel's colour does not depend on
// the strip it is drawn in.
struct Image {
  int w, h, y0, full;
  std::vector<Rgb> rgb;
  std::vector<float> inv_depth;  // 1/depth; 0 = nothing drawn (far)
};

struct ScreenVert {
  double x, y, iz;  // pixels, 1/depth
  bool visible;
};

// Fills one triangle: barycentrics in screen space, 1/depth for the
// z-test, perspective-correct normal and colour.
void draw_triangle(Image& img, const Mesh& m, const std::array<int, 3>& t,
                   const std::vector<ScreenVert>& sv, const Light& light) {
  const ScreenVert &a = sv[t[0]], &b = sv[t[1]], &c = sv[t[2]];
  if (!a.visible || !b.visible || !c.visible) return;
  const double area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
  if (std::abs(area) < 1e-12) return;
  const int x0 = std::max(0, int(std::floor(std::min({a.x, b.x, c.x}))));
  const int x1 = std::min(img.w - 1, int(std::ceil(std::max({a.x, b.x, c.x}))));
  const int y0 = std::max(img.y0, int(std::floor(std::min({a.y, b.y, c.y}))));
  const int y1 = std::min(img.y0 + img.h - 1, int(std::ceil(std::max({a.y, b.y, c.y}))));
  if (x0 > x1 || y0 > y1) return;
  const double inv_area = 1.0 / area;
  for (int y = y0; y <= y1; ++y) {
    const double py = y + 0.5;
    for (int x = x0; x <= x1; ++x) {
      const double px = x + 0.5;
      const double wa = ((b.x - px) * (c.y - py) - (b.y - py) * (c.x - px)) * inv_area;
      const double wb = ((c.x - px) * (a.y - py) - (c.y - py) * (a.x - px)) * inv_area;
      const double wc = 1.0 - wa - wb;
      if (wa < 0 || wb < 0 || wc < 0) continue;
      const double iz = wa * a.iz + wb * b.iz + wc * c.iz;
      const size_t k = size_t(y - img.y0) * img.w + x;
      if (iz <= img.inv_depth[k]) continue;
      img.inv_depth[k] = float(iz);
      // Perspective-correct weights.
      const double pa = wa * a.iz / iz, pb = wb * b.iz / iz, pc = wc * c.iz / iz;
      const V3 n = normalized(pa * m.n[t[0]] + pb * m.n[t[1]] + pc * m.n[t[2]]);
      const Rgb base = {float(pa * m.c[t[0]].r + pb * m.c[t[1]].r + pc * m.c[t[2]].r),
                        float(pa * m.c[t[0]].g + pb * m.c[t[1]].g + pc * m.c[t[2]].g),
                        float(pa * m.c[t[0]].b + pb * m.c[t[1]].b + pc * m.c[t[2]].b)};
      img.rgb[k] = scale(base, light(n));
    }
  }
}

std::vector<ScreenVert> on_screen(const Mesh& m, const Camera& cam) {
  std::vector<ScreenVert> sv(m.p.size());
  for (size_t v = 0; v < m.p.size(); ++v) {
    double d = 0;
    sv[v].visible = cam.project(m.p[v], sv[v].x, sv[v].y, d);
    sv[v].iz = sv[v].visible ? 1.0 / d : 0;
  }
  return sv;
}

void draw_mesh(Image& img, const Mesh& m, const std::vector<ScreenVert>& sv, const Light& light) {
  for (const auto& t : m.tri) draw_triangle(img, m, t, sv, light);
}

// Top-down coverage of everything above the floor, blurred: a soft shadow
// as from a broad overhead light.
struct ShadowMap {
  double x0 = 0, y0 = 0, cell = 1;
  int n = 0;
  std::vector<float> cover;
  double at(double x, double y) const {
    const int i = int((x - x0) / cell), j = int((y - y0) / cell);
    if (i < 0 || j < 0 || i >= n || j >= n) return 0;
    return cover[size_t(j) * n + i];
  }
};

void blur(std::vector<float>& a, int n, int r) {
  std::vector<float> tmp(a.size());
  for (int pass = 0; pass < 2; ++pass) {  // rows, then columns (transposed write)
    for (int j = 0; j < n; ++j) {
      double sum = 0;
      for (int i = -r; i <= r; ++i) sum += a[size_t(j) * n + std::clamp(i, 0, n - 1)];
      for (int i = 0; i < n; ++i) {
        tmp[size_t(i) * n + j] = float(sum / (2 * r + 1));
        sum += a[size_t(j) * n + std::min(i + r + 1, n - 1)] - a[size_t(j) * n + std::max(i - r, 0)];
      }
    }
    a.swap(tmp);
  }
}

ShadowMap shadow_map(const std::vector<const Mesh*>& meshes, const Box3& fit) {
  ShadowMap s;
  s.n = 256;
  const double span = std::max(fit.hi.x - fit.lo.x, fit.hi.y - fit.lo.y) * 1.2 + 1e-9;
  s.cell = span / s.n;
  s.x0 = 0.5 * (fit.lo.x + fit.hi.x) - span / 2;
  s.y0 = 0.5 * (fit.lo.y + fit.hi.y) - span / 2;
  s.cover.assign(size_t(s.n) * s.n, 0.f);
  for (const Mesh* m : meshes)
    for (const auto& t : m->tri) {
      // Mark the cells of the triangle's footprint (points at sub-cell spacing).
      const V3 a = m->p[t[0]], b = m->p[t[1]], c = m->p[t[2]];
      const double ext = std::max({std::abs(b.x - a.x), std::abs(b.y - a.y), std::abs(c.x - a.x),
                                   std::abs(c.y - a.y)});
      const int k = std::clamp(int(2 * ext / s.cell) + 1, 1, 256);
      for (int u = 0; u <= k; ++u)
        for (int v = 0; u + v <= k; ++v) {
          const V3 q = a + (double(u) / k) * (b - a) + (double(v) / k) * (c - a);
          const int i = int((q.x - s.x0) / s.cell), j = int((q.y - s.y0) / s.cell);
          if (i >= 0 && j >= 0 && i < s.n && j < s.n) s.cover[size_t(j) * s.n + i] = 1.f;
        }
    }
  blur(s.cover, s.n, 4);
  return s;
}

Rgb background(double y, int h) {
  return mix(Rgb{0.80f, 0.85f, 0.92f}, Rgb{0.97f, 0.97f, 0.98f}, y / h);
}

// Floor z = 0 by ray casting per pixel: chequer of about ten tiles across
// the cloth, fading into the background, darkened by the shadow map.
void draw_floor(Image& img, const Camera& cam, const Box3& fit, const ShadowMap& shadow,
                bool floor) {
  const V3 mid = 0.5 * (fit.lo + fit.hi);
  const double span = std::max(fit.hi.x - fit.lo.x, fit.hi.y - fit.lo.y) + 1e-9;
  const double tile = std::pow(10.0, std::floor(std::log10(span / 5)));
  const double fade0 = 0.9 * span, fade1 = 2.2 * span;
  for (int y = img.y0; y < img.y0 + img.h; ++y)
    for (int x = 0; x < img.w; ++x) {
      const size_t k = size_t(y - img.y0) * img.w + x;
      const Rgb bg = background(y, img.full);
      img.rgb[k] = bg;
      img.inv_depth[k] = 0;
      if (!floor) continue;
      const V3 ray = cam.focal * cam.fwd + (x + 0.5 - cam.cx) * cam.right - (y + 0.5 - cam.cy) * cam.up;
      if (ray.z >= 0 || cam.eye.z <= 0) continue;
      const double t = -cam.eye.z / ray.z;
      const V3 q = cam.eye + t * ray;
      const double r = std::hypot(q.x - mid.x, q.y - mid.y);
      if (r > fade1) continue;
      const bool odd = (int64_t(std::floor(q.x / tile)) + int64_t(std::floor(q.y / tile))) & 1;
      Rgb c = odd ? Rgb{0.82f, 0.82f, 0.80f} : Rgb{0.90f, 0.90f, 0.88f};
      c = scale(c, 1.0 - 0.45 * shadow.at(q.x, q.y));
      const double fade = std::clamp((r - fade0) / (fade1 - fade0), 0.0, 1.0);
      img.rgb[k] = mix(c, bg, fade * fade * (3 - 2 * fade));
      img.inv_depth[k] = float(1.0 / (t * cam.focal));  // depth = t * (ray . fwd)
    }
}

// Averages s x s blocks into 8-bit RGB: the strip's rows of `out`.
void downsample(const Image& img, int s, std::vector<uint8_t>& out) {
  const int w = img.w / s, h = img.h / s;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double r = 0, g = 0, b = 0;
      for (int dy = 0; dy < s; ++dy)
        for (int dx = 0; dx < s; ++dx) {
          const Rgb& c = img.rgb[size_t(y * s + dy) * img.w + x * s + dx];
          r += c.r, g += c.g, b += c.b;
        }
      const double norm = 255.0 / (s * s);
      uint8_t* o = &out[(size_t(img.y0 / s + y) * w + x) * 3];
      o[0] = uint8_t(std::clamp(r * norm + 0.5, 0.0, 255.0));
      o[1] = uint8_t(std::clamp(g * norm + 0.5, 0.0, 255.0));
      o[2] = uint8_t(std::clamp(b * norm + 0.5, 0.0, 255.0));
    }
}

// ------------------------------------------------------------------ PNG --

void put_u32(std::string& s, uint32_t v) {
  for (int k = 3; k >= 0; --k) s.push_back(char((v >> (8 * k)) & 0xff));
}

void put_chunk(std::string& png, const char* type, const std::string& data) {
  put_u32(png, uint32_t(data.size()));
  const size_t start = png.size();
  png.append(type, 4);
  png += data;
  const uLong crc = crc32(0L, reinterpret_cast<const Bytef*>(png.data() + start), uInt(data.size() + 4));
  put_u32(png, uint32_t(crc));
}

// 8-bit RGB, no interlace; each row with filter type 0 (none). A non-empty
// description becomes a tEXt chunk (keyword, a zero byte, Latin-1 text:
// anything but printable ASCII is written as '?').
std::string encode_png(const std::vector<uint8_t>& rgb, int w, int h, const std::string& description) {
  std::string raw;
  raw.reserve(size_t(h) * (3 * w + 1));
  for (int y = 0; y < h; ++y) {
    raw.push_back('\0');
    raw.append(reinterpret_cast<const char*>(&rgb[size_t(y) * w * 3]), size_t(w) * 3);
  }
  uLongf len = compressBound(uLong(raw.size()));
  std::string z(len, '\0');
  if (compress2(reinterpret_cast<Bytef*>(&z[0]), &len, reinterpret_cast<const Bytef*>(raw.data()),
                uLong(raw.size()), 6) != Z_OK)
    throw std::runtime_error("picture: zlib compression failed");
  z.resize(len);

  std::string png("\x89PNG\r\n\x1a\n", 8);
  std::string ihdr;
  put_u32(ihdr, uint32_t(w));
  put_u32(ihdr, uint32_t(h));
  ihdr += std::string("\x08\x02\x00\x00\x00", 5);  // depth 8, RGB, deflate, filter 0, no interlace
  put_chunk(png, "IHDR", ihdr);
  if (!description.empty()) {
    std::string text = "Description";
    text.push_back('\0');
    for (char c : description) text.push_back(c >= 0x20 && c < 0x7f ? c : '?');
    put_chunk(png, "tEXt", text);
  }
  put_chunk(png, "IDAT", z);
  put_chunk(png, "IEND", "");
  return png;
}

}  // namespace

void render_picture(const FrameView& f, const ObstacleSpec& obstacle, const std::string& path,
                    int width, int height, const std::string& description) {
  if (!f.x || f.ni < 2 || f.nj < 2) throw std::runtime_error("picture: no cloth to draw");
  render_picture(picture_surface(f), obstacle, path, width, height, description);
}

void render_picture(const PictureSurface& surface, const ObstacleSpec& obstacle, const std::string& path,
                    int width, int height, const std::string& description) {
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw std::runtime_error("picture: bad size " + std::to_string(width) + "x" + std::to_string(height));
  if (surface.mi < 2 || surface.mj < 2) throw std::runtime_error("picture: no cloth to draw");
  // 2x2 supersampling smooths the edges; skipped for huge pictures.
  const int ss = size_t(width) * height <= 4u << 20 ? 2 : 1;

  Box3 fit;
  const Mesh cloth = cloth_mesh(surface, fit);
  Mesh solid;
  if (obstacle.shape == ObstacleShape::Box) add_box(solid, obstacle, fit);
  if (obstacle.shape == ObstacleShape::Sphere) add_sphere(solid, obstacle, fit);
  if (obstacle.shape == ObstacleShape::Disc) add_disc(solid, obstacle, fit);
  if (fit.empty()) fit.add(V3{0, 0, 0});

  const int w = width * ss, h = height * ss;
  const Camera cam = frame_camera(fit, w, h);
  // Light from above the camera's shoulder, a little to its left.
  Light light;
  light.view = -1.0 * cam.fwd;
  light.dir = normalized(light.view + 0.8 * V3{0, 0, 1} - 0.35 * cam.right);

  const ShadowMap shadow = shadow_map({&cloth, &solid}, fit);
  const std::vector<ScreenVert> solid_sv = on_screen(solid, cam), cloth_sv = on_screen(cloth, cam);
  std::vector<uint8_t> rgb(size_t(width) * height * 3);
  const int rows = 32 * ss;  // a strip: a whole number of output rows
  Image img{w, 0, 0, h, std::vector<Rgb>(size_t(w) * rows), std::vector<float>(size_t(w) * rows)};
  for (img.y0 = 0; img.y0 < h; img.y0 += rows) {
    img.h = std::min(rows, h - img.y0);
    draw_floor(img, cam, fit, shadow, obstacle.floor);
    draw_mesh(img, solid, solid_sv, light);
    draw_mesh(img, cloth, cloth_sv, light);
    downsample(img, ss, rgb);
  }
  write_file_atomically(path, encode_png(rgb, width, height, description));
}

}  // namespace drape
