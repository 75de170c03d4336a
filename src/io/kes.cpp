// Fabric data loader: data/kes/<name>.toml (+ optional CSV curves) -> Fabric
// in SI. The format is described in data/kes/README.md. Every number carries
// its unit, every key is known, and every refusal names file:line and key,
// because a silently misread fabric only shows up much later as a wrong drape.
#include "io/kes.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "base/error.hpp"
#include "io/text.hpp"
#include "solver/band.hpp"

namespace drape {
namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;
constexpr double kGf = 9.80665e-3;             // N per gram-force
constexpr double kDefaultFmGfPerCm = 500.0;    // KES-FB1 standard maximum load
constexpr double kWtTolerance = 0.02;          // given WT vs LT*Fm*EMT/2

// ---------------------------------------------------------------- errors

std::string fmt_num(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

[[noreturn]] void fail(const std::string& file, int line, const std::string& key,
                       const std::string& msg) {
  std::string m = location(file, line) + ": ";
  if (!key.empty()) m += "'" + key + "': ";
  throw InputError(m + msg);
}

// ---------------------------------------------------------------- units

// One physical dimension: its accepted unit spellings and their SI factors.
struct Unit {
  const char* name;
  double to_si;
};
struct Dim {
  const char* what;  // for messages
  std::vector<Unit> units;
};

const Dim kStrain{"strain", {{"%", 0.01}, {"1", 1.0}}};
const Dim kRatio{"dimensionless ratio", {{"1", 1.0}, {"-", 1.0}}};
const Dim kForcePerWidth{"force per width", {{"gf/cm", kGf * 100.0}, {"N/m", 1.0}}};
const Dim kEnergy{"energy per area",
                  {{"gf*cm/cm^2", kGf * 100.0}, {"J/m^2", 1.0}, {"N*m/m^2", 1.0}}};
const Dim kBendRigidity{"bending rigidity",
                        {{"gf*cm^2/cm", kGf * 1e-2}, {"N*m^2/m", 1.0}, {"N*m", 1.0}}};
const Dim kMoment{"moment per width", {{"gf*cm/cm", kGf}, {"N*m/m", 1.0}, {"N", 1.0}}};
// Per degree -> per radian multiplies by 180/pi.
const Dim kShearRigidity{"shear rigidity",
                         {{"gf/cm/deg", kGf * 100.0 * 180.0 / kPi},
                          {"gf/(cm*deg)", kGf * 100.0 * 180.0 / kPi},
                          {"N/m/deg", 180.0 / kPi},
                          {"N/m/rad", 1.0},
                          {"N/(m*rad)", 1.0}}};
const Dim kLength{"length", {{"mm", 1e-3}, {"cm", 1e-2}, {"m", 1.0}}};
const Dim kAreaDensity{"mass per area",
                       {{"mg/cm^2", 1e-2},
                        {"g/m^2", 1e-3},
                        {"kg/m^2", 1.0},
                        {"oz/yd^2", 0.028349523125 / 0.83612736}}};
const Dim kCurvature{"curvature", {{"1/cm", 100.0}, {"cm^-1", 100.0}, {"1/m", 1.0}, {"m^-1", 1.0}}};
const Dim kAngle{"angle", {{"deg", kPi / 180.0}, {"rad", 1.0}}};

void replace_all(std::string& s, const std::string& from, const std::string& to) {
  for (size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size()))
    s.replace(p, from.size(), to);
}

// Spellings that differ only typographically are the same unit.
std::string normalize_unit(std::string u) {
  u.erase(std::remove_if(u.begin(), u.end(), [](unsigned char c) { return std::isspace(c); }),
          u.end());
  replace_all(u, "\xC2\xB7", "*");      // middle dot
  replace_all(u, "\xE2\x8B\x85", "*");  // dot operator
  replace_all(u, "\xC2\xB2", "^2");     // superscript two
  replace_all(u, "\xC2\xB0", "deg");    // degree sign
  replace_all(u, "degree", "deg");
  return u;
}

std::string unit_list(const Dim& d) {
  std::string s;
  for (const auto& u : d.units) s += (s.empty() ? "\"" : ", \"") + std::string(u.name) + "\"";
  return s;
}

std::optional<double> unit_factor(const Dim& d, const std::string& unit) {
  const std::string n = normalize_unit(unit);
  for (const auto& u : d.units)
    if (n == u.name) return u.to_si;
  return std::nullopt;
}

// ---------------------------------------------------------------- TOML access

struct Doc {
  std::string file;  // path as given, for messages
  fs::path dir;      // where relative curve paths start
};

// Refuses any key not in `allowed`: a typo must not silently drop a value.
void check_keys(const Doc& d, const toml::table& t, const std::string& prefix,
                std::initializer_list<const char*> allowed) {
  for (auto&& [k, v] : t) {
    bool ok = false;
    for (const char* a : allowed) ok = ok || k.str() == a;
    if (ok) continue;
    std::string list;
    for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
    fail(d.file, line_of(k), prefix + std::string(k.str()),
         "unknown key (allowed here: " + list + ")");
  }
}

const toml::table& require_table(const Doc& d, const toml::table& parent, const char* key,
                                 const std::string& prefix) {
  const toml::node* n = parent.get(key);
  if (!n) fail(d.file, line_of(parent), prefix + key, "missing required section [" + std::string(key) + "]");
  if (!n->is_table())
    fail(d.file, line_of(*n), prefix + key, std::string("expected a table, got ") + type_name(*n));
  return *n->as_table();
}

std::optional<std::string> get_string(const Doc& d, const toml::table& t, const char* key,
                                      const std::string& prefix) {
  const toml::node* n = t.get(key);
  if (!n) return std::nullopt;
  if (!n->is_string())
    fail(d.file, line_of(*n), prefix + key, std::string("expected a string, got ") + type_name(*n));
  return n->as_string()->get();
}

double get_number(const Doc& d, const toml::node& n, const std::string& key) {
  if (!n.is_number())
    fail(d.file, line_of(n), key, std::string("expected a number, got ") + type_name(n));
  const double v = *n.value<double>();
  if (!std::isfinite(v)) fail(d.file, line_of(n), key, "value must be finite");
  return v;
}

// A quantity as written: raw numbers in the file's unit, and their SI values.
struct Quantity {
  double raw[2] = {0, 0};  // [warp, weft]; equal when given as one value
  double si[2] = {0, 0};
  std::string unit;        // as written
  std::string key;         // "section.KEY"
  int line = 0;
  bool per_direction = false;
  std::string key_of(int dir) const {
    return per_direction ? key + (dir == 0 ? ".warp" : ".weft") : key;
  }
  std::string shown(int dir) const {
    const bool bare = unit == "1" || unit == "-";  // dimensionless: no unit to print
    return fmt_num(raw[dir]) + (bare ? "" : " " + unit);
  }
};

// Reads `key = { value = x, unit = "u" }` or `{ warp = a, weft = b, unit = "u" }`.
std::optional<Quantity> read_quantity(const Doc& d, const toml::table& section,
                                      const std::string& sec, const char* key, const Dim& dim,
                                      bool directional) {
  const toml::node* n = section.get(key);
  if (!n) return std::nullopt;
  Quantity q;
  q.key = sec + "." + key;
  q.line = line_of(*n);
  const std::string example = directional
      ? "write " + std::string(key) + " = { value = ..., unit = \"...\" } or { warp = ..., weft = ..., unit = \"...\" }"
      : "write " + std::string(key) + " = { value = ..., unit = \"...\" }";
  if (!n->is_table())
    fail(d.file, q.line, q.key,
         std::string("expected a number with its unit, got ") + type_name(*n) + "; " + example);
  const toml::table& t = *n->as_table();
  if (directional)
    check_keys(d, t, q.key + ".", {"value", "warp", "weft", "unit"});
  else
    check_keys(d, t, q.key + ".", {"value", "unit"});

  const auto unit = get_string(d, t, "unit", q.key + ".");
  if (!unit)
    fail(d.file, q.line, q.key,
         "missing unit (accepted for " + std::string(dim.what) + ": " + unit_list(dim) + ")");
  const auto factor = unit_factor(dim, *unit);
  if (!factor)
    fail(d.file, line_of(*t.get("unit")), q.key + ".unit",
         "unknown unit \"" + *unit + "\" for " + dim.what + " (accepted: " + unit_list(dim) + ")");
  q.unit = *unit;

  const toml::node* v = t.get("value");
  const toml::node* w[2] = {t.get("warp"), t.get("weft")};
  if (v && (w[0] || w[1]))
    fail(d.file, q.line, q.key, "give either 'value' or 'warp'/'weft', not both");
  if (v) {
    q.raw[0] = q.raw[1] = get_number(d, *v, q.key + ".value");
  } else if (w[0] || w[1]) {
    q.per_direction = true;
    for (int i = 0; i < 2; ++i) {
      const char* dn = i == 0 ? "warp" : "weft";
      if (!w[i]) fail(d.file, q.line, q.key + "." + dn, "missing (give both warp and weft)");
      q.raw[i] = get_number(d, *w[i], q.key + "." + dn);
    }
  } else {
    fail(d.file, q.line, q.key, "missing value; " + example);
  }
  for (int i = 0; i < 2; ++i) q.si[i] = q.raw[i] * *factor;
  return q;
}

Quantity require_quantity(const Doc& d, const toml::table& section, const std::string& sec,
                          const char* key, const Dim& dim, bool directional,
                          const std::string& alternative = "") {
  auto q = read_quantity(d, section, sec, key, dim, directional);
  if (!q)
    fail(d.file, line_of(section), sec + "." + key,
         "missing required key" + (alternative.empty() ? "" : " (" + alternative + ")"));
  return *q;
}

// Range checks name the value as written, so the user recognises it.
void check_positive(const Doc& d, const Quantity& q, const char* what) {
  for (int i = 0; i < 2; ++i)
    if (!(q.si[i] > 0))
      fail(d.file, q.line, q.key_of(i), std::string(what) + " must be > 0, got " + q.shown(i));
}
void check_non_negative(const Doc& d, const Quantity& q, const char* what) {
  for (int i = 0; i < 2; ++i)
    if (q.si[i] < 0)
      fail(d.file, q.line, q.key_of(i), std::string(what) + " must be >= 0, got " + q.shown(i));
}
void check_unit_interval(const Doc& d, const Quantity& q, const char* what, const char* range) {
  for (int i = 0; i < 2; ++i)
    if (!(q.si[i] > 0 && q.si[i] <= 1))
      fail(d.file, q.line, q.key_of(i), std::string(what) + " must be in " + range + ", got " + q.shown(i));
}

// ---------------------------------------------------------------- CSV curves

struct CurveSpec {
  const char* x_name;
  const Dim* x_dim;
  const char* y_name;
  const Dim* y_dim;
};
const CurveSpec kTensileCurve{"strain", &kStrain, "tension", &kForcePerWidth};
const CurveSpec kBendingCurve{"curvature", &kCurvature, "moment", &kMoment};
const CurveSpec kShearCurve{"angle", &kAngle, "force", &kForcePerWidth};

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string f;
  while (std::getline(ss, f, ',')) out.push_back(trim(f));
  if (!line.empty() && line.back() == ',') out.push_back("");
  return out;
}

// A header column "name[unit]": returns the SI factor of its unit.
double header_column(const std::string& file, int line, const std::string& col,
                     const char* name, const Dim& dim) {
  const auto open = col.find('[');
  const auto close = col.rfind(']');
  const std::string want = std::string(name) + "[" + dim.units[0].name + "]";
  if (open == std::string::npos || close == std::string::npos || close < open ||
      close != col.size() - 1)
    fail(file, line, "", "header column \"" + col + "\" has no unit: write e.g. \"" + want +
                             "\" (units: " + unit_list(dim) + ")");
  const std::string cname = trim(col.substr(0, open));
  const std::string unit = trim(col.substr(open + 1, close - open - 1));
  if (cname != name)
    fail(file, line, "", "header column \"" + col + "\": expected the column \"" + name +
                             "\" here, e.g. \"" + want + "\"");
  const auto f = unit_factor(dim, unit);
  if (!f)
    fail(file, line, "", "unknown unit \"" + unit + "\" for " + name + " (accepted: " +
                             unit_list(dim) + ")");
  return *f;
}

double parse_number(const std::string& file, int line, const std::string& field,
                    const char* column) {
  const char* s = field.c_str();
  char* end = nullptr;
  const double v = std::strtod(s, &end);
  if (field.empty() || *end != '\0' || !std::isfinite(v))
    fail(file, line, "", std::string("column ") + column + ": \"" + field + "\" is not a finite number");
  return v;
}

struct Branches {
  Curve load, unload;
  std::vector<int> load_lines, unload_lines;  // file line of each point
  std::string file;
};

// Reads a curve CSV: header "branch,<x>[unit],<y>[unit]", then rows
// "load|unload,x,y" with x strictly rising within each branch.
Branches read_curve_csv(const fs::path& path, const CurveSpec& spec) {
  Branches b;
  b.file = path.string();
  std::ifstream in(path);
  if (!in) throw InputError(b.file + ": cannot open curve file");
  std::string raw;
  int line = 0;
  bool header = false;
  double fx = 1, fy = 1;
  while (std::getline(in, raw)) {
    ++line;
    const std::string s = trim(raw);
    if (s.empty() || s[0] == '#') continue;
    const auto f = split_csv(s);
    if (!header) {
      if (f.size() != 3 || f[0] != "branch")
        fail(b.file, line, "", std::string("expected the header \"branch,") + spec.x_name + "[" +
                                   spec.x_dim->units[0].name + "]," + spec.y_name + "[" +
                                   spec.y_dim->units[0].name + "]\", got \"" + s + "\"");
      fx = header_column(b.file, line, f[1], spec.x_name, *spec.x_dim);
      fy = header_column(b.file, line, f[2], spec.y_name, *spec.y_dim);
      header = true;
      continue;
    }
    if (f.size() != 3)
      fail(b.file, line, "", "expected 3 fields \"branch,x,y\", got " + std::to_string(f.size()));
    const bool is_load = f[0] == "load";
    if (!is_load && f[0] != "unload")
      fail(b.file, line, "", "branch must be \"load\" or \"unload\", got \"" + f[0] + "\"");
    const double x = parse_number(b.file, line, f[1], spec.x_name) * fx;
    const double y = parse_number(b.file, line, f[2], spec.y_name) * fy;
    Curve& c = is_load ? b.load : b.unload;
    auto& lines = is_load ? b.load_lines : b.unload_lines;
    if (!c.q.empty() && !(x > c.q.back()))
      fail(b.file, line, "", std::string(spec.x_name) + " is not rising within the " + f[0] +
                                 " branch (previous point at line " +
                                 std::to_string(lines.back()) +
                                 "); list each branch in order of rising " + spec.x_name);
    c.q.push_back(x);
    c.f.push_back(y);
    lines.push_back(line);
  }
  if (!header) fail(b.file, 0, "", "empty curve file (no header)");
  if (b.load.q.size() < 2)
    fail(b.file, 0, "", "the load branch needs at least 2 points (rows \"load,x,y\")");
  if (b.unload.q.size() < 2)
    fail(b.file, 0, "", "the unload branch needs at least 2 points (rows \"unload,x,y\")");
  return b;
}

// Exact integral over [a, b] of the piecewise-linear interpolant (with the
// same end-segment extrapolation as interpolate() in band.cpp).
double integrate(const Curve& c, double a, double b) {
  std::vector<double> x{a};
  for (double q : c.q)
    if (q > a && q < b) x.push_back(q);
  x.push_back(b);
  double sum = 0, s = 0;
  for (size_t i = 1; i < x.size(); ++i)
    sum += 0.5 * (x[i] - x[i - 1]) * (interpolate(c, x[i - 1], &s) + interpolate(c, x[i], &s));
  return sum;
}

fs::path resolve(const Doc& d, const std::string& p) {
  const fs::path path(p);
  return path.is_absolute() ? path : d.dir / path;
}

// Tensile curves: both branches start at zero tension at a strain >= 0, never
// go below zero, and unloading lies under loading. A point at strain -1 with
// zero tension is put in front, so compression carries no tension (the band
// extrapolates end segments linearly).
TensileKES tensile_from_curve(const fs::path& path) {
  Branches b = read_curve_csv(path, kTensileCurve);
  for (int k = 0; k < 2; ++k) {
    const Curve& c = k == 0 ? b.load : b.unload;
    const auto& lines = k == 0 ? b.load_lines : b.unload_lines;
    const char* name = k == 0 ? "load" : "unload";
    if (c.q[0] < 0) fail(b.file, lines[0], "", std::string(name) + " branch starts at a negative strain");
    if (c.f[0] != 0)
      fail(b.file, lines[0], "", std::string(name) + " branch must start at zero tension");
    for (size_t i = 0; i < c.f.size(); ++i)
      if (c.f[i] < 0) fail(b.file, lines[i], "", "tension must be >= 0");
  }
  TensileKES k;
  k.emt = b.load.q.back();
  k.fm = b.load.f.back();
  if (!(k.fm > 0)) fail(b.file, b.load_lines.back(), "", "the load branch must end at a tension > 0");
  // Unloading gives back less than loading took: unload <= load on [0, EMT]
  // (checked at every breakpoint of either branch; both are linear between).
  double s = 0;
  const double tol = 1e-9 * k.fm;
  for (size_t i = 0; i < b.unload.q.size(); ++i) {
    const double q = b.unload.q[i];
    if (q <= k.emt && b.unload.f[i] > interpolate(b.load, q, &s) + tol)
      fail(b.file, b.unload_lines[i], "", "the unload branch lies above the load branch here");
  }
  for (size_t i = 0; i < b.load.q.size(); ++i)
    if (interpolate(b.unload, b.load.q[i], &s) > b.load.f[i] + tol)
      fail(b.file, b.load_lines[i], "", "the unload branch lies above the load branch here");
  for (Curve* c : {&b.load, &b.unload}) {
    c->q.insert(c->q.begin(), -1.0);
    c->f.insert(c->f.begin(), 0.0);
  }
  // KES summary of the curve, so that code reading emt/lt/rt sees the same fabric.
  const double wt = integrate(b.load, 0, k.emt);
  const double wt_back = integrate(b.unload, 0, k.emt);
  k.lt = wt / (k.fm * k.emt / 2);
  k.rt = wt_back / wt;
  if (!(k.rt > 0)) fail(b.file, 0, "", "the unload branch gives back no energy (RT = 0)");
  k.load = std::move(b.load);
  k.unload = std::move(b.unload);
  return k;
}

// Bending and shear curves: summary slope (least squares on the mid-line)
// and half loop width (mean half gap) over the range both branches cover.
void linear_summary(const Branches& b, double* slope, double* half) {
  const double lo = std::max(b.load.q.front(), b.unload.q.front());
  const double hi = std::min(b.load.q.back(), b.unload.q.back());
  if (!(hi > lo)) fail(b.file, 0, "", "the load and unload branches cover no common range");
  const int n = 201;
  double sx = 0, sy = 0, sxx = 0, sxy = 0, gap = 0, s = 0;
  for (int i = 0; i < n; ++i) {
    const double q = lo + (hi - lo) * i / (n - 1);
    const double a = interpolate(b.load, q, &s), c = interpolate(b.unload, q, &s);
    const double m = 0.5 * (a + c);
    sx += q;
    sy += m;
    sxx += q * q;
    sxy += q * m;
    gap += 0.5 * std::abs(a - c);
  }
  *slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  *half = gap / n;
  if (!(*slope > 0)) fail(b.file, 0, "", "the curve's mean slope is not positive");
}

// A bending or shear KES from its curve: the linear summary gives the
// rigidity (`slope`) and the band's half width (`half`); the branches stay.
template <class KES>
KES kes_from_curve(const fs::path& path, const CurveSpec& spec, double KES::*slope, double KES::*half) {
  Branches b = read_curve_csv(path, spec);
  KES k;
  linear_summary(b, &(k.*slope), &(k.*half));
  k.load = std::move(b.load);
  k.unload = std::move(b.unload);
  return k;
}

BendingKES bending_from_curve(const fs::path& path) {
  return kes_from_curve(path, kBendingCurve, &BendingKES::b, &BendingKES::hb);
}

ShearKES shear_from_curve(const fs::path& path) {
  return kes_from_curve(path, kShearCurve, &ShearKES::g, &ShearKES::hg);
}

// `curve = "f.csv"` (both directions) or `curve = { warp = "a.csv", weft = "b.csv" }`.
// Returns the two paths, or nothing when the section has no curve.
std::optional<std::array<fs::path, 2>> curve_paths(const Doc& d, const toml::table& sec,
                                                   const std::string& name, bool directional) {
  const toml::node* n = sec.get("curve");
  if (!n) return std::nullopt;
  const std::string key = name + ".curve";
  std::array<fs::path, 2> out;
  if (n->is_string()) {
    out[0] = out[1] = resolve(d, n->as_string()->get());
  } else if (directional && n->is_table()) {
    const toml::table& t = *n->as_table();
    check_keys(d, t, key + ".", {"warp", "weft"});
    for (int i = 0; i < 2; ++i) {
      const char* dn = i == 0 ? "warp" : "weft";
      const auto s = get_string(d, t, dn, key + ".");
      if (!s) fail(d.file, line_of(*n), key + "." + dn, "missing (give both warp and weft)");
      out[i] = resolve(d, *s);
    }
  } else {
    fail(d.file, line_of(*n), key,
         std::string("expected a CSV file name") + (directional ? " or { warp = ..., weft = ... }" : "") +
             ", got " + type_name(*n));
  }
  for (const auto& p : out)
    if (!fs::is_regular_file(p))
      fail(d.file, line_of(*n), key, "curve file " + p.string() + " does not exist");
  return out;
}

// A section gives either KES values or a curve: both at once is ambiguous.
void refuse_mixed(const Doc& d, const toml::table& sec, const std::string& name,
                  std::initializer_list<const char*> kes_keys) {
  for (const char* k : kes_keys)
    if (const toml::node* n = sec.get(k))
      fail(d.file, line_of(*n), name + "." + k,
           "this section has a 'curve': give either the curve or KES values, not both");
}

// ---------------------------------------------------------------- sections

void read_tensile(const Doc& d, const toml::table& root, Fabric& f) {
  const std::string name = "tensile";
  const toml::table& sec = require_table(d, root, "tensile", "");
  check_keys(d, sec, name + ".", {"EMT", "LT", "RT", "WT", "Fm", "curve", "notes"});
  get_string(d, sec, "notes", name + ".");
  if (auto paths = curve_paths(d, sec, name, true)) {
    refuse_mixed(d, sec, name, {"EMT", "LT", "RT", "WT", "Fm"});
    for (int i = 0; i < 2; ++i) f.tensile[i] = tensile_from_curve((*paths)[i]);
    return;
  }
  const std::string alt = "or give 'curve'";
  const Quantity emt = require_quantity(d, sec, name, "EMT", kStrain, true, alt);
  const Quantity lt = require_quantity(d, sec, name, "LT", kRatio, true, alt);
  const Quantity rt = require_quantity(d, sec, name, "RT", kStrain, true, alt);
  const auto fm = read_quantity(d, sec, name, "Fm", kForcePerWidth, true);
  const auto wt = read_quantity(d, sec, name, "WT", kEnergy, true);
  check_positive(d, emt, "EMT");
  check_unit_interval(d, lt, "LT", "(0, 1]");
  check_unit_interval(d, rt, "RT", "(0, 100] % (as a fraction: (0, 1])");
  if (fm) check_positive(d, *fm, "Fm");
  for (int i = 0; i < 2; ++i) {
    TensileKES& k = f.tensile[i];
    k.emt = emt.si[i];
    k.lt = lt.si[i];
    k.rt = rt.si[i];
    k.fm = fm ? fm->si[i] : kDefaultFmGfPerCm * kGf * 100.0;
    if (!wt) continue;
    // WT is redundant (LT is defined from it): a mismatch means a misread value.
    const double expect = k.wt();
    if (std::abs(wt->si[i] - expect) > kWtTolerance * expect)
      fail(d.file, wt->line, wt->key_of(i),
           "WT = " + wt->shown(i) + " disagrees with LT*Fm*EMT/2 = " +
               fmt_num(expect / (kGf * 100.0)) + " gf*cm/cm^2 by more than 2%");
  }
}

void read_bending(const Doc& d, const toml::table& root, Fabric& f) {
  const std::string name = "bending";
  const toml::table& sec = require_table(d, root, "bending", "");
  check_keys(d, sec, name + ".", {"B", "2HB", "curve", "notes"});
  get_string(d, sec, "notes", name + ".");
  if (auto paths = curve_paths(d, sec, name, true)) {
    refuse_mixed(d, sec, name, {"B", "2HB"});
    for (int i = 0; i < 2; ++i) f.bending[i] = bending_from_curve((*paths)[i]);
    return;
  }
  const std::string alt = "or give 'curve'";
  const Quantity b = require_quantity(d, sec, name, "B", kBendRigidity, true, alt);
  const Quantity hb2 = require_quantity(d, sec, name, "2HB", kMoment, true, alt);
  check_positive(d, b, "bending rigidity B");
  check_non_negative(d, hb2, "bending hysteresis 2HB");
  for (int i = 0; i < 2; ++i) {
    f.bending[i].b = b.si[i];
    f.bending[i].hb = hb2.si[i] / 2;  // the band's half width
  }
}

void read_shear(const Doc& d, const toml::table& root, Fabric& f) {
  const std::string name = "shear";
  const toml::table& sec = require_table(d, root, "shear", "");
  check_keys(d, sec, name + ".", {"G", "2HG", "2HG5", "curve", "notes"});
  get_string(d, sec, "notes", name + ".");
  if (auto paths = curve_paths(d, sec, name, false)) {
    refuse_mixed(d, sec, name, {"G", "2HG", "2HG5"});
    f.shear = shear_from_curve((*paths)[0]);
    return;
  }
  const std::string alt = "or give 'curve'";
  // The model has one shear band: warp/weft values are averaged, as KES's
  // summary G and 2HG are.
  const Quantity g = require_quantity(d, sec, name, "G", kShearRigidity, true, alt);
  const Quantity hg2 = require_quantity(d, sec, name, "2HG", kForcePerWidth, true, alt);
  const auto hg5 = read_quantity(d, sec, name, "2HG5", kForcePerWidth, true);
  check_positive(d, g, "shear rigidity G");
  check_non_negative(d, hg2, "shear hysteresis 2HG");
  if (hg5) check_non_negative(d, *hg5, "shear hysteresis 2HG5");  // informational only
  f.shear.g = 0.5 * (g.si[0] + g.si[1]);
  f.shear.hg = 0.25 * (hg2.si[0] + hg2.si[1]);
}

void read_physical(const Doc& d, const toml::table& root, Fabric& f) {
  const std::string name = "physical";
  const toml::table& sec = require_table(d, root, "physical", "");
  check_keys(d, sec, name + ".", {"T", "W", "notes"});
  get_string(d, sec, "notes", name + ".");
  const Quantity t = require_quantity(d, sec, name, "T", kLength, false);
  const Quantity w = require_quantity(d, sec, name, "W", kAreaDensity, false);
  check_positive(d, t, "thickness T");
  check_positive(d, w, "weight W");
  f.thickness = t.si[0];
  f.density = w.si[0];
}

std::string read_source(const Doc& d, const toml::table& root) {
  const toml::table& sec = require_table(d, root, "source", "");
  check_keys(d, sec, "source.", {"reference", "table", "column", "url", "notes"});
  const auto ref = get_string(d, sec, "reference", "source.");
  if (!ref || ref->empty())
    fail(d.file, line_of(sec), "source.reference", "missing required key (where the numbers come from)");
  std::string s = *ref;
  if (auto t = get_string(d, sec, "table", "source.")) s += "; " + *t;
  if (auto c = get_string(d, sec, "column", "source.")) s += "; column " + *c;
  if (auto u = get_string(d, sec, "url", "source.")) s += "; " + *u;
  get_string(d, sec, "notes", "source.");
  return s;
}

Fabric read_fabric_file(const fs::path& path) {
  Doc d{path.string(), path.parent_path()};
  if (!fs::is_regular_file(path)) throw InputError(d.file + ": fabric file does not exist");
  toml::table root;
  try {
    root = toml::parse_file(d.file);
  } catch (const toml::parse_error& e) {
    fail(d.file, static_cast<int>(e.source().begin.line), "",
         "TOML syntax error: " + std::string(e.description()));
  }
  check_keys(d, root, "", {"description", "source", "tensile", "bending", "shear", "physical"});
  get_string(d, root, "description", "");
  Fabric f;
  f.name = path.stem().string();
  f.source = read_source(d, root);
  read_tensile(d, root, f);
  read_bending(d, root, f);
  read_shear(d, root, f);
  read_physical(d, root, f);
  return f;
}

bool is_path(const std::string& s) {
  const std::string ext = ".toml";
  return s.find('/') != std::string::npos ||
         (s.size() >= ext.size() && s.compare(s.size() - ext.size(), ext.size(), ext) == 0);
}

// An installed program's data: DRAPE_DATA_FROM_BIN (share/drape/data, seen
// from bin/) next to the running executable, wherever the prefix was moved.
// Empty when there is none, as for a program run from the build tree.
std::string installed_data_directory() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);  // Linux
  if (ec) return "";
  const fs::path data = (exe.parent_path() / DRAPE_DATA_FROM_BIN).lexically_normal();
  return fs::is_directory(data / "kes", ec) ? data.string() : "";
}

}  // namespace

std::string kes_directory() {
  const char* env = std::getenv("DRAPE_DATA");
  if (env && *env) return std::string(env) + "/kes";
  const std::string installed = installed_data_directory();
  if (!installed.empty()) return installed + "/kes";
  return DRAPE_DATA_DIR "/kes";
}

std::vector<std::string> list_fabrics() {
  std::vector<std::string> names;
  std::error_code ec;
  for (fs::directory_iterator it(kes_directory(), ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file() && it->path().extension() == ".toml")
      names.push_back(it->path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

Fabric load_fabric(const std::string& name_or_path) {
  if (is_path(name_or_path)) return read_fabric_file(name_or_path);
  const fs::path path = fs::path(kes_directory()) / (name_or_path + ".toml");
  if (!fs::is_regular_file(path)) {
    std::string avail;
    for (const auto& n : list_fabrics()) avail += (avail.empty() ? "" : ", ") + n;
    throw InputError("unknown fabric '" + name_or_path + "': no " + path.string() +
                     "; available: " + (avail.empty() ? "(none)" : avail));
  }
  return read_fabric_file(path);
}

}  // namespace drape
