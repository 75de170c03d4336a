// Scene configuration: TOML file + --set overrides -> validated Scene.
//
// The flow: parse the file into a toml::table, merge the overrides into it
// (remembering which keys they set), refuse unknown sections and keys, read
// each key the schema declares (scene_schema.cpp) with a type check, check
// each key's own range, then the checks that involve several keys.
// Every message is one line naming the key and where its value came from:
// "file:line" for a file, "--set key=value" for an override.
#include "io/config.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cfloat>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "base/error.hpp"
#include "io/scene_schema.hpp"
#include "io/text.hpp"
#include "io/toml_text.hpp"
#include "mesh/cloth.hpp"

namespace drape {
namespace {

using Kind = ParameterKind;

const ParameterList& schema() { return scene_parameters(); }

const Parameter* find_key(const std::string& full) { return schema().find(full); }

bool is_section(const std::string& name) {
  const auto& s = schema().sections();
  return std::find(s.begin(), s.end(), name) != s.end();
}

// ---------------------------------------------------------------- errors --

// One line, always: a newline inside a user's value must not split it.
[[noreturn]] void fail(const std::string& where, const std::string& what) {
  std::string msg = where.empty() ? what : where + ": " + what;
  std::replace(msg.begin(), msg.end(), '\n', ' ');
  throw InputError(msg);
}

size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

// " (did you mean solver.dt?)" for a near miss, else "". The bare key also
// counts, so a key put in the wrong section finds its home.
std::string suggest_key(const std::string& full) {
  const auto dot = full.find('.');
  const std::string bare = dot == std::string::npos ? full : full.substr(dot + 1);
  const std::string section = dot == std::string::npos ? "" : full.substr(0, dot);
  size_t best = SIZE_MAX;
  std::string name;
  for (const Parameter& k : schema().all()) {
    const size_t d = std::min(edit_distance(full, k.full_name()),
                              edit_distance(bare, k.key) + (section == k.section ? 0 : 2));
    if (d < best) best = d, name = k.full_name();
  }
  const size_t limit = std::max<size_t>(2, bare.size() / 3);
  return best <= limit ? " (did you mean " + name + "?)" : "";
}

std::string suggest_section(const std::string& name) {
  size_t best = SIZE_MAX;
  std::string found;
  for (const std::string& s : schema().sections()) {
    const size_t d = edit_distance(name, s);
    if (d < best) best = d, found = s;
  }
  const size_t limit = std::max<size_t>(2, name.size() / 3);
  return best <= limit ? " (did you mean [" + found + "]?)" : "";
}

// ------------------------------------------------------- the merged table --

struct Config {
  toml::table root;
  std::map<std::string, std::string> overrides;  // key -> "--set key=value"

  const toml::node* node(const Parameter& k) const {
    const toml::node* n = !k.section.empty() ? root.get(k.section) : &root;
    const toml::table* t = n ? n->as_table() : nullptr;
    return t ? t->get(k.key) : nullptr;
  }
  // Where the value of `key` came from: "--set ...", "file:line" or "" (default).
  std::string where(const std::string& key) const {
    const auto o = overrides.find(key);
    if (o != overrides.end()) return o->second;
    const Parameter* k = find_key(key);
    const toml::node* n = k ? node(*k) : nullptr;
    return n ? location(n->source()) : "";
  }
};

toml::table parse_scene_text(const std::string& text, const std::string& origin) {
  try {
    return toml::parse(text, origin);
  } catch (const toml::parse_error& e) {
    const auto& b = e.source().begin;
    fail(origin + ":" + std::to_string(b.line) + ":" + std::to_string(b.column),
         "TOML syntax error: " + std::string(e.description()));
  }
}

toml::table parse_scene_file(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    fail("", "cannot open scene file '" + path + "': no such file");
  if (std::filesystem::is_directory(path, ec))
    fail("", "cannot read scene file '" + path + "': it is a directory");
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  if (!in) fail("", "cannot read scene file '" + path + "'");
  return parse_scene_text(text.str(), path);
}

// "section.key=value" into the table. Strings may be bare words
// (--set obstacle.shape=sphere); everything else is read as a TOML value.
void apply_override(Config& cfg, const std::string& text) {
  const std::string where = "--set " + text;
  const auto eq = text.find('=');
  if (eq == std::string::npos) fail(where, "expected section.key=value (no '=')");
  const std::string key = trim(text.substr(0, eq)), value = trim(text.substr(eq + 1));
  if (key.empty()) fail(where, "missing key before '='");
  const Parameter* spec = find_key(key);
  if (!spec) fail(where, "unknown key " + key + suggest_key(key));
  if (value.empty()) fail(where, key + ": missing value after '='");

  toml::table* section = &cfg.root;
  if (!spec->section.empty()) {
    if (!cfg.root.contains(spec->section)) cfg.root.insert(spec->section, toml::table{});
    section = cfg.root.get(spec->section)->as_table();
    if (!section) return;  // the file's malformed [section] is reported later
  }
  const bool quoted = value[0] == '"' || value[0] == '\'';
  if (spec->kind == Kind::String && !quoted) {
    section->insert_or_assign(spec->key, value);
  } else {
    toml::table parsed;
    try {
      parsed = toml::parse("v = " + value, std::string_view("--set"));
    } catch (const toml::parse_error&) {
      // toml++'s own words ("expected 'false', saw 'fas'") would mislead here.
      fail(where, key + ": expected " + expected_text(spec->kind) + ", got '" + value + "' (not a TOML value)");
    }
    if (parsed.size() != 1 || !parsed.contains("v"))
      fail(where, key + ": expected " + expected_text(spec->kind) + ", got '" + value + "' (more than one value)");
    section->insert_or_assign(spec->key, *parsed.get("v"));
  }
  cfg.overrides[key] = where;
}

// Unknown sections and keys. All are found and the first in the file is
// reported, so the message does not depend on the table's key order.
void refuse_unknown(const Config& cfg) {
  struct Problem {
    uint32_t line;
    std::string where, what;
  };
  std::vector<Problem> found;
  auto add = [&](const toml::source_region& src, std::string what) {
    found.push_back({src.begin.line, location(src), std::move(what)});
  };
  for (auto&& [k, node] : cfg.root) {
    const std::string name(k.str());
    if (find_key(name)) continue;  // a top-level key
    if (!is_section(name)) {
      if (node.is_table())
        add(k.source(), "unknown section [" + name + "]" + suggest_section(name));
      else
        add(k.source(), "unknown key " + name + suggest_key(name));
      continue;
    }
    const toml::table* t = node.as_table();
    if (!t) {
      add(k.source(), name + ": expected a section [" + name + "], got " + type_name(node));
      continue;
    }
    for (auto&& [kk, n] : *t) {
      const std::string full = name + "." + std::string(kk.str());
      if (!find_key(full)) add(kk.source(), "unknown key " + full + suggest_key(full));
    }
  }
  if (found.empty()) return;
  const auto first = std::min_element(found.begin(), found.end(),
                                      [](const Problem& a, const Problem& b) { return a.line < b.line; });
  fail(first->where, first->what);
}

// --------------------------------------------------------- typed reading --

// Each declared key's value from the merged table, type-checked.
class Reader {
 public:
  explicit Reader(const Config& cfg) : cfg_(cfg) {}

  // The key's value, or nothing when the scene does not give it.
  std::optional<ParameterValue> read(const Parameter& p) const {
    const toml::node* n = cfg_.node(p);
    if (!n) return std::nullopt;
    const std::string key = p.full_name();
    switch (p.kind) {
      case Kind::Int: return to_int(key, *n, p.kind);
      case Kind::Float: return to_double(key, *n, p.kind);
      case Kind::Bool: return boolean(key, *n);
      case Kind::String: return string(p, *n);
      case Kind::Int2: return array<int, 2>(key, *n, p.kind);
      case Kind::Float2: return array<double, 2>(key, *n, p.kind);
      case Kind::Float3: return array<double, 3>(key, *n, p.kind);
    }
    throw std::logic_error("config schema: " + key);
  }

 private:
  [[noreturn]] void wrong_type(const std::string& key, Kind kind, const std::string& got) const {
    fail(cfg_.where(key), key + ": expected " + expected_text(kind) + ", got " + got);
  }

  bool boolean(const std::string& key, const toml::node& n) const {
    if (!n.is_boolean()) wrong_type(key, Kind::Bool, type_name(n));
    return n.as_boolean()->get();
  }

  // An enumeration's name must be one of its choices (as to_string spells them).
  std::string string(const Parameter& p, const toml::node& n) const {
    const std::string key = p.full_name();
    if (!n.is_string()) wrong_type(key, Kind::String, type_name(n));
    const std::string text = n.as_string()->get();
    if (p.choices.empty() || std::find(p.choices.begin(), p.choices.end(), text) != p.choices.end()) return text;
    std::string names;
    for (const std::string& c : p.choices) names += (names.empty() ? "" : ", ") + c;
    fail(cfg_.where(key), key + ": must be one of " + names + "; got " + quote(text));
  }

  template <class T, size_t N>
  std::array<T, N> array(const std::string& key, const toml::node& n, Kind kind) const {
    std::array<T, N> out{};
    for (size_t i = 0; i < N; ++i) {
      const toml::node& e = element(key, n, kind, N, i);
      if constexpr (std::is_same_v<T, int>) out[i] = to_int(key, e, kind);
      else out[i] = to_double(key, e, kind);
    }
    return out;
  }

  const toml::node& element(const std::string& key, const toml::node& n, Kind kind, size_t len, size_t i) const {
    const toml::array* a = n.as_array();
    if (!a) wrong_type(key, kind, type_name(n));
    if (a->size() != len) wrong_type(key, kind, "an array of " + std::to_string(a->size()));
    return *a->get(i);
  }

  // In an array, the message names the element's position (1-based).
  std::string got(const toml::node& n, Kind kind) const {
    std::string s = type_name(n);
    return kind == Kind::Int || kind == Kind::Float ? s : s + " in the array";
  }

  int to_int(const std::string& key, const toml::node& n, Kind kind) const {
    if (!n.is_integer()) wrong_type(key, kind, got(n, kind));
    const int64_t v = n.as_integer()->get();
    if (v < INT_MIN || v > INT_MAX)
      fail(cfg_.where(key), key + ": " + std::to_string(v) + " is out of range");
    return static_cast<int>(v);
  }

  // Integers are fine for float keys (dt = 1); inf and nan are not.
  double to_double(const std::string& key, const toml::node& n, Kind kind) const {
    double v = 0;
    if (n.is_integer())
      v = static_cast<double>(n.as_integer()->get());
    else if (n.is_floating_point())
      v = n.as_floating_point()->get();
    else
      wrong_type(key, kind, got(n, kind));
    if (!std::isfinite(v)) fail(cfg_.where(key), key + ": must be a finite number, got " + format_double(v));
    return v;
  }

  const Config& cfg_;
};

void read_scene(const Config& cfg, Scene& s) {
  const Reader r(cfg);
  for (const Parameter& p : schema().all())
    if (const auto v = r.read(p)) p.set(s, *v);
}

// ------------------------------------------------------------ validation --

class Checker {
 public:
  explicit Checker(const Config& cfg) : cfg_(cfg) {}
  void operator()(bool ok, const std::string& key, const std::string& what) const {
    if (!ok) fail(cfg_.where(key), key + ": " + what);
  }
  // The key of a pair whose value the user gave, so the message points at it.
  std::string given(const std::string& a, const std::string& b) const {
    return !cfg_.where(a).empty() || cfg_.where(b).empty() ? a : b;
  }

 private:
  const Config& cfg_;
};


// Each key's own range, as the schema declares it, in declaration order.
void check_each_key(const Checker& check, const Scene& s) {
  for (const Parameter& p : schema().all()) {
    const std::string why = p.refusal(p.get(s));
    check(why.empty(), p.full_name(), why);
  }
}

// Finite sizes can still overflow what the physics derives from them: the
// area, squared edge lengths (stretch and contact square them) and the area
// a particle stands for (its mass; zero would divide later).
void check_cloth_extent(const Checker& check, const ClothSpec& c) {
  check(int64_t(c.particles[0]) * c.particles[1] <= kMaxParticles, "cloth.particles",
        "NI x NJ must be at most " + std::to_string(kMaxParticles) + ", got " + format_array(c.particles));
  const double hi = c.size[0] / (c.particles[0] - 1), hj = c.size[1] / (c.particles[1] - 1);
  check(std::isfinite(c.size[0] * c.size[1]) && std::isfinite(hi * hi) && std::isfinite(hj * hj),
        "cloth.size", "too large: the cloth's area or squared spacing is not a finite number, got " +
                          format_array(c.size));
  check(hi * hj >= DBL_MIN, "cloth.size",
        "too small: the area per particle underflows to zero, got " + format_array(c.size));
  const double reach = std::pow(std::fabs(c.center[0]) + 0.5 * c.size[0], 2) +
                       std::pow(std::fabs(c.center[1]) + 0.5 * c.size[1], 2) + c.height * c.height;
  check(std::isfinite(reach), check.given("cloth.size", "cloth.center"),
        "too large: the cloth's squared reach from the origin is not a finite number (cloth.center " +
            format_array(c.center) + ", cloth.height " + format_double(c.height) + ", cloth.size " +
            format_array(c.size) + ")");
}

void check_cloth_placement(const Checker& check, const Scene& s) {
  const auto& c = s.cloth;
  check(c.clamp >= 0 && c.clamp < c.particles[0], "cloth.clamp",
        "must be in [0, NI), got " + std::to_string(c.clamp));
  check(!s.obstacle.floor || c.height >= 0, "cloth.height",
        "must be >= 0 (the cloth starts above the floor; obstacle.floor = true), got " + format_double(c.height));
}

// Contact squares distances to the obstacle: its farthest point's squared
// distance from the origin must stay finite.
void check_obstacle_extent(const Checker& check, const ObstacleSpec& o) {
  double box = 0, ball = 0;
  for (int k = 0; k < 3; ++k) {
    box += std::pow(std::fabs(o.center[k]) + 0.5 * o.size[k], 2);
    ball += std::pow(std::fabs(o.center[k]) + o.radius, 2);
  }
  check(std::isfinite(box), check.given("obstacle.size", "obstacle.center"),
        "too large: the box's squared reach is not a finite number (obstacle.center " + format_array(o.center) +
            ", obstacle.size " + format_array(o.size) + ")");
  check(std::isfinite(ball), check.given("obstacle.radius", "obstacle.center"),
        "too large: the sphere's squared reach is not a finite number (obstacle.center " +
            format_array(o.center) + ", obstacle.radius " + format_double(o.radius) + ")");
}

void check_time_steps(const Checker& check, const SolverSpec& v) {
  check(v.dt_min <= v.dt_max, check.given("solver.dt_min", "solver.dt_max"),
        "solver.dt_min (" + format_double(v.dt_min) + ") must be <= solver.dt_max (" +
            format_double(v.dt_max) + ")");
  const std::string bound = v.dt < v.dt_min ? "solver.dt_min" : "solver.dt_max";
  check(v.dt_min <= v.dt && v.dt <= v.dt_max, check.given("solver.dt", bound),
        "solver.dt must lie in [solver.dt_min, solver.dt_max] = [" + format_double(v.dt_min) + ", " +
            format_double(v.dt_max) + "], got " + format_double(v.dt));
}

// The circular specimen is cut from the finest grid once: AMRC's quadtree
// knows nothing of the cut (grid sequencing is left out for it, run.cpp).
void check_cloth_shape(const Checker& check, const Scene& s) {
  const auto& c = s.cloth;
  if (c.shape != ClothShape::Disc) return;
  check(c.size[0] == c.size[1], "cloth.size",
        "cloth.shape = \"disc\" cuts the disc of diameter cloth.size from a square: the two sizes must be "
        "equal, got " + format_array(c.size));
  check(!s.amrc.enabled, "amrc.enabled", "cloth.shape = \"disc\" runs on the finest mesh: set amrc.enabled = false");
}

void check_amrc_thresholds(const Checker& check, const AmrcSpec& a) {
  check(a.coarsen >= 0 && a.coarsen < a.refine, check.given("amrc.coarsen", "amrc.refine"),
        "amrc.coarsen must be in [0, amrc.refine) = [0, " + format_double(a.refine) + "), got " +
            format_double(a.coarsen));
}

// Each key alone first, then what involves several keys (or several
// elements of one), which may rely on each being in range.
void validate(const Config& cfg, const Scene& s) {
  const Checker check(cfg);
  check_each_key(check, s);
  check_cloth_extent(check, s.cloth);
  check_cloth_placement(check, s);
  check_cloth_shape(check, s);
  check_obstacle_extent(check, s.obstacle);
  check_time_steps(check, s.solver);
  check_amrc_thresholds(check, s.amrc);
}

Scene resolve(Config& cfg, const std::vector<std::string>& overrides) {
  for (const std::string& o : overrides) apply_override(cfg, o);
  refuse_unknown(cfg);
  Scene s;  // its defaults are the embedded default scene
  read_scene(cfg, s);
  validate(cfg, s);
  return s;
}

}  // namespace

Scene load_scene(const std::optional<std::string>& path, const std::vector<std::string>& overrides) {
  Config cfg;
  if (path) cfg.root = parse_scene_file(*path);
  return resolve(cfg, overrides);
}

Scene load_scene_text(const std::string& toml, const std::string& origin,
                      const std::vector<std::string>& overrides) {
  Config cfg;
  cfg.root = parse_scene_text(toml, origin);
  return resolve(cfg, overrides);
}

void check_restart_overrides(const std::vector<std::string>& overrides) {
  // What may change when a run continues: how long, how it is written and
  // how it is run; never the physics, or the restart would not continue it.
  static const char* const allowed[] = {"solver.steps", "solver.end_time", "solver.wall_limit", "amrc.last_level",
                                        "output.", "parallel."};
  for (const std::string& o : overrides) {
    const std::string key = trim(o.substr(0, o.find('=')));
    bool ok = false;
    for (const char* a : allowed) ok = ok || key == a || (a[std::strlen(a) - 1] == '.' && key.rfind(a, 0) == 0);
    if (!ok)
      fail("--set " + o, key + " cannot change on --restart (the checkpoint fixes the physics); "
                          "allowed: solver.steps, solver.end_time, solver.wall_limit, amrc.last_level, output.*, "
                          "parallel.*");
  }
}

bool overrides_key(const std::vector<std::string>& overrides, const std::string& key) {
  for (const std::string& o : overrides)
    if (trim(o.substr(0, o.find('='))) == key) return true;
  return false;
}

void check_particle_mass(const Scene& s, double density, const std::string& fabric) {
  const auto& c = s.cloth;
  const double mass = density * (c.size[0] / (c.particles[0] - 1)) * (c.size[1] / (c.particles[1] - 1));
  // The weight, and the contact stiffness 10^4 weights over a distance, are
  // derived from it: keep a margin of those factors below overflow.
  if (!(mass >= DBL_MIN) || !std::isfinite(mass * 1e6))
    fail("", "cloth.size: a particle's mass (fabric " + fabric + "'s " + format_double(density) +
                 " kg/m^2 times its area) is not a usable number, got " + format_double(mass) +
                 " kg for cloth.size = " + format_array(c.size) + " and cloth.particles = " +
                 format_array(c.particles));
}

std::string scene_to_toml(const Scene& s) { return parameters_to_toml(schema(), s); }

std::string scene_reference() { return parameters_to_markdown(schema(), Scene{}); }

}  // namespace drape
