// Scene configuration: TOML file + --set overrides -> validated Scene.
//
// The flow: parse the file into a toml::table, merge the overrides into it
// (remembering which keys they set), refuse unknown sections and keys, read
// each known key with a type check, then check ranges on the resolved Scene.
// Every message is one line naming the key and where its value came from:
// "file:line" for a file, "--set key=value" for an override.
#include "io/config.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <charconv>
#include <climits>
#include <cmath>
#include <cfloat>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <sstream>
#include <stdexcept>

#include "io/error.hpp"
#include "io/text.hpp"
#include "solver/cloth.hpp"

namespace drape {
namespace {

// ---------------------------------------------------------------- schema --

enum class Kind { Int, Float, Bool, String, Int2, Float2, Float3 };

struct KeySpec {
  const char* section;  // "" for a top-level key
  const char* key;
  Kind kind;
};

// Exactly the fields of scene.hpp. A new key goes here and in read_scene(),
// validate() and scene_to_toml().
const KeySpec kKeys[] = {
    {"", "name", Kind::String},
    {"cloth", "particles", Kind::Int2},
    {"cloth", "size", Kind::Float2},
    {"cloth", "fabric", Kind::String},
    {"cloth", "tile", Kind::Int},
    {"cloth", "shear", Kind::Bool},
    {"cloth", "clamp", Kind::Int},
    {"cloth", "bend_reversal", Kind::Float},
    {"cloth", "shear_reversal", Kind::Float},
    {"cloth", "stretch_reversal", Kind::Float},
    {"cloth", "compression", Kind::Float},
    {"cloth", "height", Kind::Float},
    {"cloth", "center", Kind::Float2},
    {"obstacle", "shape", Kind::String},
    {"obstacle", "center", Kind::Float3},
    {"obstacle", "size", Kind::Float3},
    {"obstacle", "radius", Kind::Float},
    {"obstacle", "floor", Kind::Bool},
    {"solver", "dt", Kind::Float},
    {"solver", "dt_min", Kind::Float},
    {"solver", "dt_max", Kind::Float},
    {"solver", "steps", Kind::Int},
    {"solver", "max_iterations", Kind::Int},
    {"solver", "tolerance", Kind::Float},
    {"solver", "gradient", Kind::String},
    {"solver", "method", Kind::String},
    {"solver", "preconditioner", Kind::String},
    {"solver", "damping", Kind::Float},
    {"solver", "rest_speed", Kind::Float},
    {"solver", "contact_thickness", Kind::Float},
    {"solver", "memory", Kind::Float},
    {"solver", "drag", Kind::Float},
    {"solver", "wall_limit", Kind::Float},
    {"solver", "end_time", Kind::Float},
    {"output", "every", Kind::Int},
    {"output", "picture", Kind::Bool},
    {"output", "checkpoint_every", Kind::Int},
    {"parallel", "schedule", Kind::String},
    {"parallel", "chunk", Kind::Int},
    {"parallel", "threads", Kind::Int},
    {"parallel", "imbalance", Kind::Float},
    {"amrc", "enabled", Kind::Bool},
    {"amrc", "max_level", Kind::Int},
    {"amrc", "refine", Kind::Float},
    {"amrc", "coarsen", Kind::Float},
    {"amrc", "every", Kind::Int},
    {"amrc", "coarsen_speed", Kind::Float},
    {"amrc", "indicator", Kind::String},
    {"amrc", "start_spacing", Kind::Float},
    {"amrc", "stage_drag", Kind::Float},
};

const char* const kSections[] = {"cloth", "obstacle", "solver", "output", "parallel", "amrc"};

std::string full_name(const KeySpec& k) {
  return *k.section ? std::string(k.section) + "." + k.key : std::string(k.key);
}

const KeySpec* find_key(const std::string& full) {
  for (const KeySpec& k : kKeys)
    if (full_name(k) == full) return &k;
  return nullptr;
}

bool is_section(const std::string& name) {
  for (const char* s : kSections)
    if (name == s) return true;
  return false;
}

const char* expected(Kind k) {
  switch (k) {
    case Kind::Int: return "an integer";
    case Kind::Float: return "a number";
    case Kind::Bool: return "a boolean (true or false)";
    case Kind::String: return "a string";
    case Kind::Int2: return "an array of 2 integers";
    case Kind::Float2: return "an array of 2 numbers";
    case Kind::Float3: return "an array of 3 numbers";
  }
  return "?";
}

// ------------------------------------------------------------ formatting --

// Shortest text that reads back to exactly `v`, always a TOML float. Like
// Python's repr: plain digits for 1e-4 <= |v| < 1e16, else an exponent.
std::string format_double(double v) {
  char buf[400];  // room for the longest fixed-notation double
  const double a = std::fabs(v);
  const auto form = a == 0 || (a >= 1e-4 && a < 1e16) ? std::chars_format::fixed
                                                       : std::chars_format::scientific;
  const auto r = std::to_chars(buf, buf + sizeof buf, v, form);
  std::string s(buf, r.ptr);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // "1" -> "1.0"
  return s;
}

template <class T, size_t N>
std::string format_array(const std::array<T, N>& a) {
  std::string s = "[";
  for (size_t i = 0; i < N; ++i) {
    if (i) s += ", ";
    if constexpr (std::is_floating_point_v<T>)
      s += format_double(a[i]);
    else
      s += std::to_string(a[i]);
  }
  return s + "]";
}

// A TOML basic string: quotes, backslashes and control characters escaped.
std::string quote(const std::string& text) {
  std::string s = "\"";
  for (unsigned char c : text) {
    switch (c) {
      case '"': s += "\\\""; break;
      case '\\': s += "\\\\"; break;
      case '\n': s += "\\n"; break;
      case '\t': s += "\\t"; break;
      case '\r': s += "\\r"; break;
      default:
        if (c < 0x20 || c == 0x7f) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04X", c);
          s += buf;
        } else {
          s += static_cast<char>(c);
        }
    }
  }
  return s + "\"";
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
  for (const KeySpec& k : kKeys) {
    const size_t d = std::min(edit_distance(full, full_name(k)),
                              edit_distance(bare, k.key) + (section == k.section ? 0 : 2));
    if (d < best) best = d, name = full_name(k);
  }
  const size_t limit = std::max<size_t>(2, bare.size() / 3);
  return best <= limit ? " (did you mean " + name + "?)" : "";
}

std::string suggest_section(const std::string& name) {
  size_t best = SIZE_MAX;
  std::string found;
  for (const char* s : kSections) {
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

  const toml::node* node(const KeySpec& k) const {
    const toml::node* n = *k.section ? root.get(k.section) : &root;
    const toml::table* t = n ? n->as_table() : nullptr;
    return t ? t->get(k.key) : nullptr;
  }
  // Where the value of `key` came from: "--set ...", "file:line" or "" (default).
  std::string where(const std::string& key) const {
    const auto o = overrides.find(key);
    if (o != overrides.end()) return o->second;
    const KeySpec* k = find_key(key);
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
  const KeySpec* spec = find_key(key);
  if (!spec) fail(where, "unknown key " + key + suggest_key(key));
  if (value.empty()) fail(where, key + ": missing value after '='");

  toml::table* section = &cfg.root;
  if (*spec->section) {
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
      fail(where, key + ": expected " + expected(spec->kind) + ", got '" + value + "' (not a TOML value)");
    }
    if (parsed.size() != 1 || !parsed.contains("v"))
      fail(where, key + ": expected " + expected(spec->kind) + ", got '" + value + "' (more than one value)");
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
    if (name == "name") continue;
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

class Reader {
 public:
  explicit Reader(const Config& cfg) : cfg_(cfg) {}

  void get(const char* key, int& out) { if (auto* n = find(key, Kind::Int)) out = to_int(key, *n, Kind::Int); }
  void get(const char* key, double& out) { if (auto* n = find(key, Kind::Float)) out = to_double(key, *n, Kind::Float); }
  void get(const char* key, bool& out) {
    if (auto* n = find(key, Kind::Bool)) {
      if (!n->is_boolean()) wrong_type(key, Kind::Bool, type_name(*n));
      out = n->as_boolean()->get();
    }
  }
  bool get(const char* key, std::string& out) {
    const toml::node* n = find(key, Kind::String);
    if (!n) return false;
    if (!n->is_string()) wrong_type(key, Kind::String, type_name(*n));
    out = n->as_string()->get();
    return true;
  }
  void get(const char* key, std::array<int, 2>& out) {
    if (auto* n = find(key, Kind::Int2))
      for (size_t i = 0; i < 2; ++i) out[i] = to_int(key, element(key, *n, Kind::Int2, 2, i), Kind::Int2);
  }
  template <size_t N>
  void get(const char* key, std::array<double, N>& out) {
    const Kind kind = N == 2 ? Kind::Float2 : Kind::Float3;
    if (auto* n = find(key, kind))
      for (size_t i = 0; i < N; ++i) out[i] = to_double(key, element(key, *n, kind, N, i), kind);
  }

  // A string key naming one of an enumeration's values (as to_string spells them).
  template <class E>
  void get_enum(const char* key, E& out, std::initializer_list<E> all) {
    std::string text;
    if (!get(key, text)) return;
    std::string names;
    for (E e : all) {
      if (text == to_string(e)) {
        out = e;
        return;
      }
      names += std::string(names.empty() ? "" : ", ") + to_string(e);
    }
    fail(cfg_.where(key), std::string(key) + ": must be one of " + names + "; got " + quote(text));
  }

 private:
  // The key's node, or null when not given. The schema and the reader must
  // agree on the kind: a mismatch is a bug here, not bad input.
  const toml::node* find(const char* key, Kind kind) const {
    const KeySpec* k = find_key(key);
    if (!k || k->kind != kind) throw std::logic_error(std::string("config schema: ") + key);
    return cfg_.node(*k);
  }

  [[noreturn]] void wrong_type(const std::string& key, Kind kind, const std::string& got) const {
    fail(cfg_.where(key), key + ": expected " + expected(kind) + ", got " + got);
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
  Reader r(cfg);
  r.get("name", s.name);
  r.get("cloth.particles", s.cloth.particles);
  r.get("cloth.size", s.cloth.size);
  r.get("cloth.fabric", s.cloth.fabric);
  r.get("cloth.tile", s.cloth.tile);
  r.get("cloth.shear", s.cloth.shear);
  r.get("cloth.clamp", s.cloth.clamp);
  r.get("cloth.bend_reversal", s.cloth.bend_reversal);
  r.get("cloth.shear_reversal", s.cloth.shear_reversal);
  r.get("cloth.stretch_reversal", s.cloth.stretch_reversal);
  r.get("cloth.compression", s.cloth.compression);
  r.get("cloth.height", s.cloth.height);
  r.get("cloth.center", s.cloth.center);
  r.get_enum("obstacle.shape", s.obstacle.shape,
             {ObstacleShape::Box, ObstacleShape::Sphere, ObstacleShape::None});
  r.get("obstacle.center", s.obstacle.center);
  r.get("obstacle.size", s.obstacle.size);
  r.get("obstacle.radius", s.obstacle.radius);
  r.get("obstacle.floor", s.obstacle.floor);
  r.get("solver.dt", s.solver.dt);
  r.get("solver.dt_min", s.solver.dt_min);
  r.get("solver.dt_max", s.solver.dt_max);
  r.get("solver.steps", s.solver.steps);
  r.get("solver.max_iterations", s.solver.max_iterations);
  r.get("solver.tolerance", s.solver.tolerance);
  r.get_enum("solver.gradient", s.solver.gradient, {GradientMode::Analytic, GradientMode::Numeric});
  r.get_enum("solver.method", s.solver.method, {SolverMethod::Newton, SolverMethod::Cg});
  r.get_enum("solver.preconditioner", s.solver.preconditioner, {Preconditioner::Jacobi, Preconditioner::Multigrid});
  r.get("solver.damping", s.solver.damping);
  r.get("solver.rest_speed", s.solver.rest_speed);
  r.get("solver.contact_thickness", s.solver.contact_thickness);
  r.get("solver.memory", s.solver.memory);
  r.get("solver.drag", s.solver.drag);
  r.get("solver.wall_limit", s.solver.wall_limit);
  r.get("solver.end_time", s.solver.end_time);
  r.get("output.every", s.output.every);
  r.get("output.picture", s.output.picture);
  r.get("output.checkpoint_every", s.output.checkpoint_every);
  r.get_enum("parallel.schedule", s.parallel.schedule,
             {Schedule::ActiveLists, Schedule::Static, Schedule::Dynamic, Schedule::Guided});
  r.get("parallel.chunk", s.parallel.chunk);
  r.get("parallel.threads", s.parallel.threads);
  r.get("parallel.imbalance", s.parallel.imbalance);
  r.get("amrc.enabled", s.amrc.enabled);
  r.get("amrc.max_level", s.amrc.max_level);
  r.get("amrc.refine", s.amrc.refine);
  r.get("amrc.coarsen", s.amrc.coarsen);
  r.get("amrc.every", s.amrc.every);
  r.get("amrc.coarsen_speed", s.amrc.coarsen_speed);
  r.get_enum("amrc.indicator", s.amrc.indicator, {AmrcIndicator::Angle, AmrcIndicator::Deflection});
  r.get("amrc.start_spacing", s.amrc.start_spacing);
  r.get("amrc.stage_drag", s.amrc.stage_drag);
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

template <class T, size_t N>
bool all_positive(const std::array<T, N>& a) {
  return std::all_of(a.begin(), a.end(), [](T v) { return v > 0; });
}

void validate(const Config& cfg, const Scene& s) {
  const Checker check(cfg);
  const auto got = [](double v) { return ", got " + format_double(v); };
  const auto& c = s.cloth;
  check(!s.name.empty(), "name", "must not be empty");
  check(c.particles[0] >= 3 && c.particles[1] >= 3, "cloth.particles",
        "NI and NJ must each be >= 3, got " + format_array(c.particles));
  check(int64_t(c.particles[0]) * c.particles[1] <= kMaxParticles, "cloth.particles",
        "NI x NJ must be at most " + std::to_string(kMaxParticles) + ", got " + format_array(c.particles));
  check(all_positive(c.size), "cloth.size", "sizes must be > 0, got " + format_array(c.size));
  {
    // Finite sizes can still overflow what the physics derives from them: the
    // area, squared edge lengths (stretch and contact square them) and the
    // area a particle stands for (its mass; zero would divide later).
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
  check(!c.fabric.empty(), "cloth.fabric", "must not be empty");
  check(c.tile >= 2, "cloth.tile", "must be >= 2, got " + std::to_string(c.tile));
  check(c.clamp >= 0 && c.clamp < c.particles[0], "cloth.clamp",
        "must be in [0, NI), got " + std::to_string(c.clamp));
  // At 1 a linear band's force never meets an edge again: no hysteresis.
  for (const auto& [key, r] : {std::pair{"cloth.bend_reversal", c.bend_reversal},
                               std::pair{"cloth.shear_reversal", c.shear_reversal}})
    check(r == 0 || r > 1, key, "must be 0 (the band taken literally) or > 1" + got(r));
  check(c.stretch_reversal == 0 || c.stretch_reversal >= 1, "cloth.stretch_reversal",
        "must be 0 (the band taken literally) or >= 1" + got(c.stretch_reversal));
  check(c.compression >= 0 && c.compression <= 1, "cloth.compression",
        "must be in [0, 1]" + got(c.compression));
  check(!s.obstacle.floor || c.height >= 0, "cloth.height",
        "must be >= 0 (the cloth starts above the floor; obstacle.floor = true)" + got(c.height));

  const auto& o = s.obstacle;
  check(all_positive(o.size), "obstacle.size", "sizes must be > 0, got " + format_array(o.size));
  check(o.radius > 0, "obstacle.radius", "must be > 0" + got(o.radius));
  // Contact squares distances to the obstacle: its farthest point's squared
  // distance from the origin must stay finite.
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

  const auto& v = s.solver;
  check(v.dt > 0, "solver.dt", "must be > 0" + got(v.dt));
  check(v.dt_min > 0, "solver.dt_min", "must be > 0" + got(v.dt_min));
  check(v.dt_max > 0, "solver.dt_max", "must be > 0" + got(v.dt_max));
  check(v.dt_min <= v.dt_max, check.given("solver.dt_min", "solver.dt_max"),
        "solver.dt_min (" + format_double(v.dt_min) + ") must be <= solver.dt_max (" +
            format_double(v.dt_max) + ")");
  const std::string bound = v.dt < v.dt_min ? "solver.dt_min" : "solver.dt_max";
  check(v.dt_min <= v.dt && v.dt <= v.dt_max, check.given("solver.dt", bound),
        "solver.dt must lie in [solver.dt_min, solver.dt_max] = [" + format_double(v.dt_min) + ", " +
            format_double(v.dt_max) + "]" + got(v.dt));
  check(v.steps >= 1, "solver.steps", "must be >= 1, got " + std::to_string(v.steps));
  check(v.max_iterations >= 1, "solver.max_iterations",
        "must be >= 1, got " + std::to_string(v.max_iterations));
  check(v.tolerance > 0, "solver.tolerance", "must be > 0" + got(v.tolerance));
  check(v.damping >= 0 && v.damping < 1, "solver.damping", "must be in [0, 1)" + got(v.damping));
  check(v.rest_speed >= 0, "solver.rest_speed", "must be >= 0" + got(v.rest_speed));
  check(v.memory >= 0, "solver.memory", "must be >= 0" + got(v.memory));
  check(v.drag >= 0, "solver.drag", "must be >= 0" + got(v.drag));
  check(v.wall_limit >= 0, "solver.wall_limit", "must be >= 0 (0: no limit)" + got(v.wall_limit));
  check(v.end_time >= 0, "solver.end_time", "must be >= 0 (0: no limit)" + got(v.end_time));
  check(v.contact_thickness >= 0, "solver.contact_thickness",
        "must be >= 0 (0: automatic)" + got(v.contact_thickness));

  check(s.output.every >= 0, "output.every", "must be >= 0, got " + std::to_string(s.output.every));
  check(s.output.checkpoint_every >= 0, "output.checkpoint_every",
        "must be >= 0 (0: only on a signal or the wall limit), got " +
            std::to_string(s.output.checkpoint_every));
  check(s.parallel.chunk >= 1, "parallel.chunk", "must be >= 1, got " + std::to_string(s.parallel.chunk));
  check(s.parallel.threads >= 0 && s.parallel.threads <= 1024, "parallel.threads",
        "must be in [0, 1024] (0: OpenMP default), got " + std::to_string(s.parallel.threads));
  check(s.parallel.imbalance >= 1.0, "parallel.imbalance",
        "must be >= 1 (max / mean work per rank)" + got(s.parallel.imbalance));
  const auto& a = s.amrc;
  check(a.max_level >= 0 && a.max_level <= 10, "amrc.max_level",
        "must be in [0, 10], got " + std::to_string(a.max_level));
  check(a.refine > 0, "amrc.refine", "must be > 0 (rad)" + got(a.refine));
  check(a.coarsen >= 0 && a.coarsen < a.refine, check.given("amrc.coarsen", "amrc.refine"),
        "amrc.coarsen must be in [0, amrc.refine) = [0, " + format_double(a.refine) + ")" + got(a.coarsen));
  check(a.every >= 1, "amrc.every", "must be >= 1, got " + std::to_string(a.every));
  check(a.coarsen_speed >= 0, "amrc.coarsen_speed", "must be >= 0 (m/s; 0: no speed condition)" + got(a.coarsen_speed));
  check(a.start_spacing >= 0, "amrc.start_spacing",
        "must be >= 0 (m; 0: the run starts on the finest mesh)" + got(a.start_spacing));
  check(a.stage_drag >= 0, "amrc.stage_drag", "must be >= 0 (1/s)" + got(a.stage_drag));
}

// ----------------------------------------------------------------- output --

// "key = value  # comment", comments aligned for reading.
void line(std::ostringstream& os, const char* key, const std::string& value, const char* comment) {
  std::string kv = std::string(key) + " = " + value;
  if (*comment) kv.resize(std::max<size_t>(kv.size() + 1, 34), ' '), kv += std::string("# ") + comment;
  os << kv << "\n";
}

std::string b(bool v) { return v ? "true" : "false"; }

}  // namespace

namespace {

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
  static const char* const allowed[] = {"solver.steps", "solver.end_time", "solver.wall_limit", "output.",
                                        "parallel."};
  for (const std::string& o : overrides) {
    const std::string key = trim(o.substr(0, o.find('=')));
    bool ok = false;
    for (const char* a : allowed) ok = ok || key == a || (a[std::strlen(a) - 1] == '.' && key.rfind(a, 0) == 0);
    if (!ok)
      fail("--set " + o, key + " cannot change on --restart (the checkpoint fixes the physics); "
                          "allowed: solver.steps, solver.end_time, solver.wall_limit, output.*, parallel.*");
  }
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

std::string scene_to_toml(const Scene& s) {
  std::ostringstream os;
  os << "# drape scene, fully resolved (SI units)\n";
  line(os, "name", quote(s.name), "");
  const auto& c = s.cloth;
  os << "\n[cloth]\n";
  line(os, "particles", format_array(c.particles), "NI (warp), NJ (weft)");
  line(os, "size", format_array(c.size), "m along i, j");
  line(os, "fabric", quote(c.fabric), "name in data/kes/ or a path");
  line(os, "tile", std::to_string(c.tile), "particles per tile side");
  line(os, "shear", b(c.shear), "KES shear band");
  line(os, "clamp", std::to_string(c.clamp), "rows i < clamp held fixed (a platform); 0: none");
  line(os, "bend_reversal", format_double(c.bend_reversal),
       "slope inside the bending band / loading slope (0 literal band, > 1 KES reversal)");
  line(os, "shear_reversal", format_double(c.shear_reversal), "the same for shear");
  line(os, "stretch_reversal", format_double(c.stretch_reversal),
       "stretch: the same (1: along the loading curve's slope)");
  line(os, "compression", format_double(c.compression),
       "compressive modulus / the tensile test's Fm/EMT (0: no resistance)");
  line(os, "height", format_double(c.height), "m, z of the flat cloth at t = 0");
  line(os, "center", format_array(c.center), "m, x-y of the cloth centre");
  const auto& o = s.obstacle;
  os << "\n[obstacle]\n";
  line(os, "shape", quote(to_string(o.shape)), "box | sphere | none");
  line(os, "center", format_array(o.center), "m");
  line(os, "size", format_array(o.size), "m, box edge lengths");
  line(os, "radius", format_double(o.radius), "m, sphere");
  line(os, "floor", b(o.floor), "plane z = 0");
  const auto& v = s.solver;
  os << "\n[solver]\n";
  line(os, "dt", format_double(v.dt), "s, first step (adaptive afterwards)");
  line(os, "dt_min", format_double(v.dt_min), "s");
  line(os, "dt_max", format_double(v.dt_max), "s");
  line(os, "steps", std::to_string(v.steps), "time steps at most");
  line(os, "max_iterations", std::to_string(v.max_iterations), "CG iterations per step at most");
  line(os, "tolerance", format_double(v.tolerance), "cost per active particle");
  line(os, "gradient", quote(to_string(v.gradient)), "analytic | numeric");
  line(os, "method", quote(to_string(v.method)), "newton (Newton + linear CG) | cg (the paper's nonlinear CG)");
  line(os, "preconditioner", quote(to_string(v.preconditioner)),
       "newton's linear CG: jacobi | multigrid (one rank)");
  line(os, "damping", format_double(v.damping), "fraction of velocity removed per step");
  line(os, "rest_speed", format_double(v.rest_speed), "m/s; > 0 stops once at rest");
  line(os, "contact_thickness", format_double(v.contact_thickness), "m; 0 = automatic");
  line(os, "memory", format_double(v.memory), "weight of the force memory (hysteresis) term");
  line(os, "drag", format_double(v.drag), "1/s: air drag, a force -drag*m*v on each particle");
  line(os, "wall_limit", format_double(v.wall_limit), "s; stop stepping after this long (0: no limit)");
  line(os, "end_time", format_double(v.end_time), "s of simulated time; stop once reached (0: no limit)");
  os << "\n[output]\n";
  line(os, "every", std::to_string(s.output.every), "frame every N steps (0: final only)");
  line(os, "picture", b(s.output.picture), "drape.png of the final state");
  line(os, "checkpoint_every", std::to_string(s.output.checkpoint_every),
       "checkpoint.h5 every N steps and at the end (0: on a signal or the wall limit only)");
  const auto& p = s.parallel;
  os << "\n[parallel]\n";
  line(os, "schedule", quote(to_string(p.schedule)), "active-lists | static | dynamic | guided");
  line(os, "chunk", std::to_string(p.chunk), "tiles per chunk (dynamic schedule)");
  line(os, "threads", std::to_string(p.threads), "0: OMP_NUM_THREADS / OpenMP default");
  line(os, "imbalance", format_double(p.imbalance), "max / mean work per rank that triggers a rebalance after AMRC");
  const auto& a = s.amrc;
  os << "\n[amrc]\n";
  line(os, "enabled", b(a.enabled), "adaptive refinement and coarsening");
  line(os, "max_level", std::to_string(a.max_level), "coarsest leaves span 2^max_level intervals");
  line(os, "refine", format_double(a.refine), "rad: split where a triple turns more");
  line(os, "coarsen", format_double(a.coarsen), "rad: merge where all turn less (< refine)");
  line(os, "every", std::to_string(a.every), "steps between adaptations");
  line(os, "coarsen_speed", format_double(a.coarsen_speed), "m/s: merge only where all are slower (0: off)");
  line(os, "indicator", quote(to_string(a.indicator)),
       "angle | deflection (the angle times the leaf's width over the coarsest's)");
  line(os, "start_spacing", format_double(a.start_spacing),
       "m: start this coarse (AMRC: leaves this wide; else refine at each rest); 0: finest");
  line(os, "stage_drag", format_double(a.stage_drag), "1/s: air drag on every mesh while grid sequencing");
  return os.str();
}

}  // namespace drape
