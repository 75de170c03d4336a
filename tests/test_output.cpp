// Output writers on one rank: drape.h5 read back with the HDF5 C API, the
// XDMF description, temporary names, and the PNG picture decoded with zlib.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <mpi.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "base/error.hpp"
#include "io/h5.hpp"
#include "io/output.hpp"
#include "mesh/cloth.hpp"
#include "support/files.hpp"

namespace fs = std::filesystem;
using namespace drape;

namespace {

std::string fresh_dir(const std::string& name) {
  const fs::path d = fs::path(DRAPE_TEST_TMP) / ("output_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d.string();
}

bool exists(const std::string& dir, const char* name) { return fs::exists(fs::path(dir) / name); }

using test::slurp;

// A frame whose every value encodes its particle, component and step, so
// a value in the wrong place cannot go unnoticed.
struct Synthetic {
  int ni, nj, step;
  double time;
  std::vector<double> x, tension, moment, shear;
  std::vector<uint8_t> flags, level;

  Synthetic(int ni_, int nj_, int step_) : ni(ni_), nj(nj_), step(step_), time(step_ * 1e-3) {
    const int n = ni * nj;
    for (int p = 0; p < n; ++p) {
      for (int c = 0; c < 3; ++c) x.push_back(step * 1e4 + p * 10 + c + 0.125);
      for (int c = 0; c < 2; ++c) tension.push_back(-(step * 1e4 + p * 10 + c + 0.5));
      for (int c = 0; c < 2; ++c) moment.push_back((step * 1e4 + p * 10 + c) * 1e-6);
      shear.push_back(p + step * 0.25);
      flags.push_back(p % 5 == 0 ? 0 : p % 7 == 0 ? (kActive | kFixed) : kActive);
      level.push_back(uint8_t((p + step) % 4));
    }
  }
  FrameView view() const {
    FrameView f;
    f.ni = ni, f.nj = nj, f.step = step, f.time = time;
    f.x = x.data(), f.tension = tension.data(), f.moment = moment.data();
    f.shear = shear.data(), f.flags = flags.data(), f.level = level.data();
    f.owned = {{0, ni, 0, nj}};
    return f;
  }
};

const char* kToml = "name = \"box-drape-test\"\n# <markup> & \"quotes\" stay as they are\n"
                    "[cloth]\nparticles = [7, 5]\n";

Scene test_scene() {
  Scene s;
  s.name = "box-drape-test";
  s.obstacle.shape = ObstacleShape::Box;
  return s;
}

Fabric test_fabric() {
  Fabric f;
  f.name = "denim-T";
  f.source = "Synthetic test fabric, no source";
  f.density = 0.42;
  f.thickness = 7e-4;
  f.tensile[0].emt = 0.051;
  f.tensile[1].emt = 0.062;
  f.bending[0].b = 1.1e-5;
  f.bending[1].b = 0.9e-5;
  f.shear.g = 85.0;
  return f;
}

void write_run(const std::string& dir, int ni, int nj, const std::vector<int>& steps,
               const std::string& toml = kToml) {
  Hdf5Output out(dir, MPI_COMM_WORLD, test_scene(), toml, test_fabric(), ni, nj);
  for (int s : steps) out.write_frame(Synthetic(ni, nj, s).view());
  out.finish();
}

// ------------------------------------------------------------ HDF5 reads --

struct Id {
  hid_t id;
  herr_t (*close)(hid_t);
  ~Id() {
    if (id >= 0) close(id);
  }
};

std::vector<hsize_t> dims_of(hid_t file, const std::string& path) {
  Id ds{H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose};
  if (ds.id < 0) return {};
  Id sp{H5Dget_space(ds.id), H5Sclose};
  std::vector<hsize_t> d(H5Sget_simple_extent_ndims(sp.id));
  H5Sget_simple_extent_dims(sp.id, d.data(), nullptr);
  return d;
}

template <class T>
std::vector<T> read_all(hid_t file, const std::string& path, hid_t mem_type) {
  size_t n = 1;
  for (hsize_t d : dims_of(file, path)) n *= d;
  std::vector<T> v(n);
  Id ds{H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose};
  EXPECT_GE(ds.id, 0) << path;
  EXPECT_GE(H5Dread(ds.id, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), 0) << path;
  return v;
}

std::string string_attr(hid_t obj, const char* name) {
  Id a{H5Aopen(obj, name, H5P_DEFAULT), H5Aclose};
  if (a.id < 0) return "<missing>";
  Id t{H5Aget_type(a.id), H5Tclose};
  EXPECT_EQ(H5Tget_class(t.id), H5T_STRING) << name;
  std::vector<char> buf(H5Tget_size(t.id) + 1, '\0');
  H5Aread(a.id, t.id, buf.data());
  return buf.data();
}

std::vector<double> double_attr(hid_t obj, const char* name) {
  Id a{H5Aopen(obj, name, H5P_DEFAULT), H5Aclose};
  if (a.id < 0) return {};
  Id sp{H5Aget_space(a.id), H5Sclose};
  std::vector<double> v(H5Sget_simple_extent_npoints(sp.id));
  H5Aread(a.id, H5T_NATIVE_DOUBLE, v.data());
  return v;
}

int64_t int_attr(hid_t obj, const char* name) {
  Id a{H5Aopen(obj, name, H5P_DEFAULT), H5Aclose};
  int64_t v = -999;
  if (a.id >= 0) H5Aread(a.id, H5T_NATIVE_INT64, &v);
  return v;
}

std::vector<std::string> members(hid_t file, const char* group) {
  Id g{H5Gopen2(file, group, H5P_DEFAULT), H5Gclose};
  std::vector<std::string> names;
  H5Literate(
      g.id, H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
        static_cast<std::vector<std::string>*>(data)->push_back(name);
        return 0;
      },
      &names);
  return names;
}

void expect_frame(hid_t file, const Synthetic& s) {
  char name[32];
  std::snprintf(name, sizeof name, "/frames/%06d", s.step);
  const std::string g = name;
  const hsize_t ni = s.ni, nj = s.nj;
  EXPECT_EQ(dims_of(file, g + "/positions"), (std::vector<hsize_t>{ni, nj, 3}));
  EXPECT_EQ(dims_of(file, g + "/tension"), (std::vector<hsize_t>{ni, nj, 2}));
  EXPECT_EQ(dims_of(file, g + "/moment"), (std::vector<hsize_t>{ni, nj, 2}));
  EXPECT_EQ(dims_of(file, g + "/shear"), (std::vector<hsize_t>{ni, nj}));
  EXPECT_EQ(dims_of(file, g + "/active"), (std::vector<hsize_t>{ni, nj}));
  EXPECT_EQ(dims_of(file, g + "/level"), (std::vector<hsize_t>{ni, nj}));
  EXPECT_EQ(read_all<double>(file, g + "/positions", H5T_NATIVE_DOUBLE), s.x);
  EXPECT_EQ(read_all<double>(file, g + "/tension", H5T_NATIVE_DOUBLE), s.tension);
  EXPECT_EQ(read_all<double>(file, g + "/moment", H5T_NATIVE_DOUBLE), s.moment);
  EXPECT_EQ(read_all<double>(file, g + "/shear", H5T_NATIVE_DOUBLE), s.shear);
  EXPECT_EQ(read_all<uint8_t>(file, g + "/level", H5T_NATIVE_UINT8), s.level);
  EXPECT_EQ(read_all<uint8_t>(file, g + "/flags", H5T_NATIVE_UINT8), s.flags);
  std::vector<uint8_t> active;
  for (uint8_t f : s.flags) active.push_back(f & kActive);
  EXPECT_EQ(read_all<uint8_t>(file, g + "/active", H5T_NATIVE_UINT8), active);
  Id grp{H5Gopen2(file, g.c_str(), H5P_DEFAULT), H5Gclose};
  EXPECT_EQ(int_attr(grp.id, "step"), s.step);
  EXPECT_EQ(double_attr(grp.id, "time"), std::vector<double>{s.time});
}

// ---------------------------------------------------------------- XML --

size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// Every element closes, in order: enough to catch a broken writer.
bool tags_balance(const std::string& xml) {
  std::vector<std::string> open;
  for (size_t at = xml.find('<'); at != std::string::npos; at = xml.find('<', at + 1)) {
    const size_t end = xml.find('>', at);
    if (end == std::string::npos) return false;
    const std::string tag = xml.substr(at + 1, end - at - 1);
    if (tag.empty() || tag[0] == '?' || tag[0] == '!') continue;
    const bool closing = tag[0] == '/', empty = tag.back() == '/';
    const std::string name = tag.substr(closing, tag.find_first_of(" /", closing) - closing);
    if (closing) {
      if (open.empty() || open.back() != name) return false;
      open.pop_back();
    } else if (!empty) {
      open.push_back(name);
    }
  }
  return open.empty();
}

// ----------------------------------------------------------------- PNG --

struct Png {
  uint32_t width = 0, height = 0;
  int depth = 0, colour = 0;
  std::vector<uint8_t> rgb;  // decoded, unfiltered
  std::string error;
  std::vector<std::pair<std::string, std::string>> text;  // tEXt chunks: keyword, text
};

uint32_t be32(const std::string& s, size_t at) {
  return uint32_t(uint8_t(s[at])) << 24 | uint32_t(uint8_t(s[at + 1])) << 16 |
         uint32_t(uint8_t(s[at + 2])) << 8 | uint32_t(uint8_t(s[at + 3]));
}

int paeth(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

// Reverses the five PNG row filters (3 bytes per pixel).
bool unfilter(const std::vector<uint8_t>& raw, Png& png) {
  const size_t stride = size_t(png.width) * 3;
  png.rgb.assign(stride * png.height, 0);
  for (size_t y = 0; y < png.height; ++y) {
    const uint8_t type = raw[y * (stride + 1)];
    const uint8_t* in = &raw[y * (stride + 1) + 1];
    uint8_t* out = &png.rgb[y * stride];
    const uint8_t* up = y ? out - stride : nullptr;
    for (size_t k = 0; k < stride; ++k) {
      const int a = k >= 3 ? out[k - 3] : 0, b = up ? up[k] : 0, c = up && k >= 3 ? up[k - 3] : 0;
      int pred = 0;
      switch (type) {
        case 0: pred = 0; break;
        case 1: pred = a; break;
        case 2: pred = b; break;
        case 3: pred = (a + b) / 2; break;
        case 4: pred = paeth(a, b, c); break;
        default: return false;
      }
      out[k] = uint8_t(in[k] + pred);
    }
  }
  return true;
}

Png decode_png(const std::string& path) {
  Png png;
  const std::string s = slurp(path);
  if (s.size() < 8 || s.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) != 0) {
    png.error = "bad signature";
    return png;
  }
  std::string idat;
  bool ended = false;
  for (size_t at = 8; at + 12 <= s.size() && !ended;) {
    const uint32_t len = be32(s, at);
    const std::string type = s.substr(at + 4, 4);
    if (at + 12 + len > s.size()) break;
    const uint32_t crc = uint32_t(crc32(0L, reinterpret_cast<const Bytef*>(&s[at + 4]), len + 4));
    if (crc != be32(s, at + 8 + len)) png.error = "bad CRC in " + type;
    const std::string data = s.substr(at + 8, len);
    if (type == "IHDR") {
      png.width = be32(data, 0), png.height = be32(data, 4);
      png.depth = uint8_t(data[8]), png.colour = uint8_t(data[9]);
    } else if (type == "IDAT") {
      idat += data;
    } else if (type == "tEXt") {
      const size_t zero = data.find('\0');
      if (zero == std::string::npos) png.error = "tEXt without a keyword";
      else png.text.emplace_back(data.substr(0, zero), data.substr(zero + 1));
    } else if (type == "IEND") {
      ended = true;
    }
    at += 12 + len;
  }
  if (!ended && png.error.empty()) png.error = "no IEND";
  if (!png.error.empty() || png.depth != 8 || png.colour != 2) return png;
  std::vector<uint8_t> raw(size_t(png.height) * (size_t(png.width) * 3 + 1));
  uLongf n = raw.size();
  if (uncompress(raw.data(), &n, reinterpret_cast<const Bytef*>(idat.data()), idat.size()) != Z_OK ||
      n != raw.size())
    png.error = "IDAT does not inflate to the image size";
  else if (!unfilter(raw, png))
    png.error = "bad filter type";
  return png;
}

double luminance_variance(const Png& png) {
  double sum = 0, sum2 = 0;
  const size_t n = size_t(png.width) * png.height;
  for (size_t k = 0; k < n; ++k) {
    const double l = 0.3 * png.rgb[3 * k] + 0.59 * png.rgb[3 * k + 1] + 0.11 * png.rgb[3 * k + 2];
    sum += l, sum2 += l * l;
  }
  return sum2 / n - (sum / n) * (sum / n);
}

size_t distinct_colours(const Png& png) {
  std::set<uint32_t> c;
  for (size_t k = 0; k + 2 < png.rgb.size(); k += 3)
    c.insert(uint32_t(png.rgb[k]) << 16 | uint32_t(png.rgb[k + 1]) << 8 | png.rgb[k + 2]);
  return c.size();
}

// A 1 m cloth that lies on a 0.4 m box and hangs down its sides to the
// floor, with folds: not physics, just the shape of a drape.
struct Drape {
  int n;
  std::vector<double> x;
  std::vector<uint8_t> flags;
  explicit Drape(int n_) : n(n_), x(size_t(n_) * n_ * 3), flags(size_t(n_) * n_, kActive) {
    const double half = 0.2, top = 0.4 + 0.005;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const double u = -0.5 + double(i) / (n - 1), v = -0.5 + double(j) / (n - 1);
        // Distance along the cloth from the box's top face, and the outward direction.
        const double du = std::max(0.0, std::abs(u) - half), dv = std::max(0.0, std::abs(v) - half);
        const double s = std::hypot(du, dv);
        double ox = s > 0 ? std::copysign(du / s, u) : 0, oy = s > 0 ? std::copysign(dv / s, v) : 0;
        const double angle = std::atan2(v, u);
        const double hang = std::max(0.0, s - 0.03), drop = std::min(hang, top - 0.005);
        const double spread = 0.03 + 0.25 * drop + (hang - drop);  // flare, then lies on the floor
        const double fold = 0.035 * std::min(1.0, hang / 0.2) * std::sin(12 * angle);
        double* q = &x[(size_t(i) * n + j) * 3];
        q[0] = std::copysign(std::min(std::abs(u), half), u) + ox * (s > 0 ? std::min(s, spread) : 0) +
               fold * -oy;
        q[1] = std::copysign(std::min(std::abs(v), half), v) + oy * (s > 0 ? std::min(s, spread) : 0) +
               fold * ox;
        q[2] = top - drop;
      }
  }
  FrameView view() const {
    FrameView f;
    f.ni = f.nj = n;
    f.x = x.data();
    f.flags = flags.data();
    f.owned = {{0, n, 0, n}};
    return f;
  }
};

ObstacleSpec box_obstacle() {
  ObstacleSpec ob;
  ob.shape = ObstacleShape::Box;
  ob.center = {0, 0, 0.2};
  ob.size = {0.4, 0.4, 0.4};
  ob.floor = true;
  return ob;
}

void expect_picture(const std::string& path, uint32_t w, uint32_t h) {
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  const Png png = decode_png(path);
  ASSERT_EQ(png.error, "");
  EXPECT_EQ(png.width, w);
  EXPECT_EQ(png.height, h);
  EXPECT_EQ(png.depth, 8);
  EXPECT_EQ(png.colour, 2);
  EXPECT_GT(luminance_variance(png), 100.0);
  EXPECT_GT(distinct_colours(png), 200u);
}

}  // namespace

// ------------------------------------------------------------------ tests --

TEST(Hdf5Output, FramesReadBackExactly) {
  const std::string dir = fresh_dir("frames");
  write_run(dir, 7, 5, {10, 20});
  EXPECT_TRUE(exists(dir, "drape.h5"));
  EXPECT_FALSE(exists(dir, "drape.h5.tmp"));

  Id file{H5Fopen((dir + "/drape.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  ASSERT_GE(file.id, 0);
  EXPECT_EQ(members(file.id, "/frames"), (std::vector<std::string>{"000010", "000020"}));
  expect_frame(file.id, Synthetic(7, 5, 10));
  expect_frame(file.id, Synthetic(7, 5, 20));
}

TEST(Hdf5Output, RootAttributesDescribeTheRun) {
  const std::string dir = fresh_dir("attributes");
  write_run(dir, 7, 5, {3});
  Id file{H5Fopen((dir + "/drape.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  ASSERT_GE(file.id, 0);
  const hid_t f = file.id;
  EXPECT_EQ(string_attr(f, "scene"), "box-drape-test");
  EXPECT_EQ(string_attr(f, "scene_toml"), kToml);
  EXPECT_EQ(string_attr(f, "fabric"), "denim-T");
  EXPECT_EQ(string_attr(f, "fabric_source"), "Synthetic test fabric, no source");
  EXPECT_EQ(string_attr(f, "obstacle_shape"), to_string(ObstacleShape::Box));
  EXPECT_NE(string_attr(f, "drape_version"), "");
  EXPECT_NE(string_attr(f, "drape_version"), "<missing>");
  EXPECT_EQ(double_attr(f, "fabric_density"), std::vector<double>{0.42});
  EXPECT_EQ(double_attr(f, "fabric_thickness"), std::vector<double>{7e-4});
  EXPECT_EQ(double_attr(f, "kes_emt"), (std::vector<double>{0.051, 0.062}));
  EXPECT_EQ(double_attr(f, "kes_b"), (std::vector<double>{1.1e-5, 0.9e-5}));
  EXPECT_EQ(double_attr(f, "kes_g"), std::vector<double>{85.0});
  const Fabric fab = test_fabric();
  EXPECT_EQ(double_attr(f, "kes_wt"), (std::vector<double>{fab.tensile[0].wt(), fab.tensile[1].wt()}));
  EXPECT_EQ(double_attr(f, "kes_lt").size(), 2u);
  EXPECT_EQ(double_attr(f, "kes_rt").size(), 2u);
  EXPECT_EQ(double_attr(f, "kes_hb").size(), 2u);
  EXPECT_EQ(double_attr(f, "kes_hg").size(), 1u);
  EXPECT_EQ(int_attr(f, "ni"), 7);
  EXPECT_EQ(int_attr(f, "nj"), 5);
}

TEST(Hdf5Output, QuadsCoverTheGridCounterClockwise) {
  const std::string dir = fresh_dir("quads");
  const int ni = 7, nj = 5;
  write_run(dir, ni, nj, {1});
  Id file{H5Fopen((dir + "/drape.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  ASSERT_GE(file.id, 0);
  const hsize_t nq = (ni - 1) * (nj - 1);
  EXPECT_EQ(dims_of(file.id, "/mesh/quads"), (std::vector<hsize_t>{nq, 4}));
  const auto q = read_all<int32_t>(file.id, "/mesh/quads", H5T_NATIVE_INT32);
  ASSERT_EQ(q.size(), nq * 4);
  std::set<int32_t> used;
  for (hsize_t k = 0; k < nq; ++k) {
    // Signed area in the (i, j) plane: positive is counter-clockwise.
    double area = 0;
    for (int c = 0; c < 4; ++c) {
      const int32_t a = q[4 * k + c], b = q[4 * k + (c + 1) % 4];
      area += double(a / nj) * (b % nj) - double(b / nj) * (a % nj);
      used.insert(a);
    }
    EXPECT_DOUBLE_EQ(area / 2, 1.0) << "quad " << k;
  }
  EXPECT_EQ(used.size(), size_t(ni * nj));
  EXPECT_EQ(q[0], 0);
  EXPECT_EQ(q[1], nj);
  EXPECT_EQ(q[2], nj + 1);
  EXPECT_EQ(q[3], 1);
}

TEST(Hdf5Output, XdmfNamesEveryFrame) {
  const std::string dir = fresh_dir("xdmf");
  write_run(dir, 7, 5, {10, 20});
  EXPECT_TRUE(exists(dir, "drape.xdmf"));
  EXPECT_FALSE(exists(dir, "drape.xdmf.tmp"));
  const std::string x = slurp(dir + "/drape.xdmf");
  EXPECT_TRUE(tags_balance(x)) << x;
  EXPECT_EQ(count(x, "<Grid"), 3u);  // the temporal collection + one per frame
  EXPECT_EQ(count(x, "</Grid>"), 3u);
  EXPECT_EQ(count(x, "CollectionType=\"Temporal\""), 1u);
  EXPECT_EQ(count(x, "TopologyType=\"Quadrilateral\""), 2u);
  EXPECT_EQ(count(x, "drape.h5:/mesh/quads"), 2u);
  EXPECT_EQ(count(x, "NumberOfElements=\"24\""), 2u);
  EXPECT_EQ(count(x, "<Time Value=\"0.01\"/>"), 1u);
  EXPECT_EQ(count(x, "<Time Value=\"0.02\"/>"), 1u);
  for (const char* f : {"000010", "000020"})
    for (const char* d : {"positions", "tension", "moment", "shear", "active", "level"}) {
      const std::string ref = std::string("drape.h5:/frames/") + f + "/" + d + "<";
      EXPECT_GE(count(x, ref), 1u) << ref;
    }
  // (warp, weft) pairs as two-component node arrays.
  for (const char* name : {"tension", "moment"})
    EXPECT_EQ(count(x, std::string("Name=\"") + name + "\" AttributeType=\"Matrix\""), 2u) << name;
  EXPECT_EQ(count(x, "Dimensions=\"7 5 2\""), 4u);
  EXPECT_EQ(count(x, "Dimensions=\"7 5 3\""), 2u);
}

TEST(Hdf5Output, LongSceneTextIsKept) {
  // Beyond the 64 KiB of a compact attribute.
  std::string toml;
  while (toml.size() < 100000) toml += "# a long comment line that pads the scene text\n";
  const std::string dir = fresh_dir("long_toml");
  write_run(dir, 4, 3, {0}, toml);
  Id file{H5Fopen((dir + "/drape.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  ASSERT_GE(file.id, 0);
  EXPECT_EQ(string_attr(file.id, "scene_toml"), toml);
}

TEST(Hdf5Output, DestroyWithoutFinishLeavesNothing) {
  const std::string dir = fresh_dir("abandon");
  {
    Hdf5Output out(dir, MPI_COMM_WORLD, test_scene(), kToml, test_fabric(), 7, 5);
    out.write_frame(Synthetic(7, 5, 1).view());
    EXPECT_TRUE(exists(dir, "drape.h5.tmp"));
  }
  EXPECT_FALSE(exists(dir, "drape.h5"));
  EXPECT_FALSE(exists(dir, "drape.h5.tmp"));
  EXPECT_FALSE(exists(dir, "drape.xdmf"));
}

TEST(Hdf5Output, RepeatedStepIsRefusedAndNothingIsLeft) {
  const std::string dir = fresh_dir("repeat");
  {
    Hdf5Output out(dir, MPI_COMM_WORLD, test_scene(), kToml, test_fabric(), 7, 5);
    out.write_frame(Synthetic(7, 5, 10).view());
    EXPECT_THROW(out.write_frame(Synthetic(7, 5, 10).view()), std::runtime_error);  // HDF5's own
    // A frame of the wrong shape is found before any collective call, and
    // all ranks agree on it.
    EXPECT_THROW(out.write_frame(Synthetic(6, 5, 11).view()), CollectiveError);
  }
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(Hdf5Output, MissingDirectoryIsAClearError) {
  const std::string dir = fresh_dir("missing") + "/not/there";
  try {
    Hdf5Output out(dir, MPI_COMM_WORLD, test_scene(), kToml, test_fabric(), 7, 5);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(dir + "/drape.h5.tmp"), std::string::npos) << e.what();
  }
}

TEST(Picture, DrapeOverBoxIsAShadedPng) {
  const std::string dir = fresh_dir("picture_box");
  const Drape d(81);
  render_picture(d.view(), box_obstacle(), dir + "/drape.png", 320, 240);
  expect_picture(dir + "/drape.png", 320, 240);
}

// The description goes in as one tEXt chunk, "Description", printable ASCII
// (anything else as '?'); the image is the same as without it. None: no chunk.
TEST(Picture, DescriptionIsATextChunk) {
  const std::string dir = fresh_dir("picture_text");
  const Drape d(33);
  render_picture(d.view(), box_obstacle(), dir + "/plain.png", 160, 120);
  render_picture(d.view(), box_obstacle(), dir + "/text.png", 160, 120,
                 "box-drape, 33 x 33 grid: on the level-1 mesh, 289 particles solved\xc3\x97");
  const Png plain = decode_png(dir + "/plain.png"), text = decode_png(dir + "/text.png");
  ASSERT_EQ(plain.error, "");
  ASSERT_EQ(text.error, "");
  EXPECT_TRUE(plain.text.empty());
  ASSERT_EQ(text.text.size(), 1u);
  EXPECT_EQ(text.text[0].first, "Description");
  EXPECT_EQ(text.text[0].second, "box-drape, 33 x 33 grid: on the level-1 mesh, 289 particles solved??");
  EXPECT_EQ(text.rgb, plain.rgb);
}

TEST(Picture, SphereWithoutFloorAndNoObstacle) {
  const std::string dir = fresh_dir("picture_other");
  const Drape d(33);
  ObstacleSpec sphere = box_obstacle();
  sphere.shape = ObstacleShape::Sphere;
  sphere.radius = 0.2;
  sphere.floor = false;
  render_picture(d.view(), sphere, dir + "/sphere.png", 200, 150);
  expect_picture(dir + "/sphere.png", 200, 150);
  ObstacleSpec none = sphere;
  none.shape = ObstacleShape::None;
  render_picture(d.view(), none, dir + "/none.png", 150, 200);
  expect_picture(dir + "/none.png", 150, 200);
}

TEST(Picture, InactiveParticlesAreSkippedOrFilled) {
  // AMRC leaves particles inside coarse cells inactive (positions unused):
  // here every other row and column, with NaN where they are inactive.
  const std::string dir = fresh_dir("picture_amrc");
  Drape d(65);
  for (int i = 0; i < d.n; ++i)
    for (int j = 0; j < d.n; ++j)
      if (i % 2 || j % 2) {
        d.flags[size_t(i) * d.n + j] = 0;
        for (int c = 0; c < 3; ++c) d.x[(size_t(i) * d.n + j) * 3 + c] = NAN;
      }
  render_picture(d.view(), box_obstacle(), dir + "/amrc.png", 240, 180);
  expect_picture(dir + "/amrc.png", 240, 180);
}

TEST(Picture, BadArgumentsThrow) {
  const std::string dir = fresh_dir("picture_bad");
  const Drape d(5);
  EXPECT_THROW(render_picture(d.view(), box_obstacle(), dir + "/a.png", 0, 10), std::runtime_error);
  EXPECT_THROW(render_picture(d.view(), box_obstacle(), dir + "/no/such/dir/a.png", 10, 10),
               std::runtime_error);
  EXPECT_TRUE(fs::is_empty(dir));
}

// The full-size grid renders (subsampled) to a valid picture. Its speed is a
// benchmark figure, not a test: shared machines are too noisy for timings.
TEST(Picture, MillionParticlesRender) {
  const std::string dir = fresh_dir("picture_big");
  const Drape d(1000);
  render_picture(d.view(), box_obstacle(), dir + "/drape.png", 1024, 768);
  expect_picture(dir + "/drape.png", 1024, 768);
}

// h5::read_particles reads a rank's held particles' rows: a dataset whose
// every value encodes its particle and component, read back for sets of
// particles with gaps, runs ending at a row's end and starting a row, a
// single particle and none, each value where the set's order puts it.
TEST(Hdf5Read, HeldParticlesComeBackInTheirOrder) {
  const std::string dir = fresh_dir("read_particles");
  const int ni = 7, nj = 5, comps = 3;
  auto value = [](int64_t p, int k) { return 1000.0 * double(p) + k; };
  std::vector<double> all(size_t(ni * nj * comps));
  for (int64_t p = 0; p < ni * nj; ++p)
    for (int k = 0; k < comps; ++k) all[size_t(3 * p + k)] = value(p, k);
  const std::string path = dir + "/grid.h5";
  {
    const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    const hsize_t dims[3] = {hsize_t(ni), hsize_t(nj), hsize_t(comps)};
    const hid_t space = H5Screate_simple(3, dims, nullptr);
    const hid_t ds = H5Dcreate2(f, "x", H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, all.data()), 0);
    H5Dclose(ds);
    H5Sclose(space);
    H5Fclose(f);
  }
  const std::vector<std::vector<int64_t>> sets = {
      {0, 1, 2, 3, 4, 5, 6},         // a whole row and the next one's start
      {3, 4, 5, 6, 12, 20, 21, 34},  // a run across a row's end, gaps, the last particle
      {17},
      {},
  };
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  for (const std::vector<int64_t>& ids : sets) {
    std::vector<double> got(ids.size() * comps + 1, -1.0);
    h5::read_particles(f, "x", H5T_NATIVE_DOUBLE, ni, nj, comps, &ids, got.data());
    for (size_t k = 0; k < ids.size(); ++k)
      for (int c = 0; c < comps; ++c) EXPECT_EQ(got[3 * k + size_t(c)], value(ids[k], c)) << ids[k] << "." << c;
    EXPECT_EQ(got.back(), -1.0) << "read past the held particles";
  }
  std::vector<double> whole(all.size());
  h5::read_particles(f, "x", H5T_NATIVE_DOUBLE, ni, nj, comps, nullptr, whole.data());
  EXPECT_EQ(whole, all);
  // The wrong shape is refused, naming the dataset.
  const std::vector<int64_t> one = {0};
  double v[2];
  EXPECT_THROW(h5::read_particles(f, "x", H5T_NATIVE_DOUBLE, ni, nj, 2, &one, v), std::runtime_error);
  H5Fclose(f);
}
