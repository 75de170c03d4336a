#pragma once
// A schema of scene keys: each key is declared once, binding its name to a
// Scene member with its unit, allowed values and documentation. Reading,
// range checks, --dry-run's text and the configuration reference all walk
// the same declarations, so they cannot drift apart.
#include <array>
#include <cstring>
#include <functional>
#include <initializer_list>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "io/bound.hpp"
#include "solver/scene.hpp"

namespace drape {

// A key's value, by the C++ type of its member (an enumeration is its name).
using ParameterValue = std::variant<int, double, bool, std::string, std::array<int, 2>,
                                    std::array<double, 2>, std::array<double, 3>>;

// The TOML shape a key takes; the order follows ParameterValue's.
enum class ParameterKind { Int, Float, Bool, String, Int2, Float2, Float3 };

// "an integer", "an array of 2 numbers": what a wrong type was expected to be.
const char* expected_text(ParameterKind k);

struct Parameter {
  std::string section;  // "" for a top-level key
  std::string key;
  ParameterKind kind;
  std::string unit;     // "m", "1/s"; "" for none
  Bound bound;
  std::vector<std::string> choices;  // an enumeration's names; empty otherwise
  std::string comment;  // after the value in --dry-run's text
  std::string doc;      // the reference's meaning column
  std::string example;  // a value other than the default that passes the checks
  std::function<ParameterValue(const Scene&)> get;
  std::function<void(Scene&, const ParameterValue&)> set;
  // Whether two scenes hold the same value here, bit for bit (-0.0 is not 0.0).
  std::function<bool(const Scene&, const Scene&)> same;

  std::string full_name() const { return section.empty() ? key : section + "." + key; }
  // The example as a TOML value: a string (an enumeration's too) quoted.
  std::string example_toml() const;
  // "must be > 0, got -1", or "" when `v` is allowed.
  std::string refusal(const ParameterValue& v) const;
};

// The value as TOML text: 1.0, [3, 3], "box".
std::string value_text(const ParameterValue& v);

// Bit for bit for numbers and arrays of them (so -0.0 and the last ulp
// count), == for strings.
template <class T>
bool same_bits(const T& a, const T& b) {
  if constexpr (std::is_trivially_copyable_v<T>) return std::memcmp(&a, &b, sizeof a) == 0;
  else return a == b;
}

template <class T>
constexpr ParameterKind kind_of() {
  if constexpr (std::is_same_v<T, int>) return ParameterKind::Int;
  else if constexpr (std::is_same_v<T, double>) return ParameterKind::Float;
  else if constexpr (std::is_same_v<T, bool>) return ParameterKind::Bool;
  else if constexpr (std::is_same_v<T, std::array<int, 2>>) return ParameterKind::Int2;
  else if constexpr (std::is_same_v<T, std::array<double, 2>>) return ParameterKind::Float2;
  else if constexpr (std::is_same_v<T, std::array<double, 3>>) return ParameterKind::Float3;
  else return ParameterKind::String;  // std::string and enumerations
}

class ParameterList;

// The keys of one [section], bound to the Scene member S that holds them
// (the top level: S = Scene). add() returns *this, one line per key.
template <class S>
class SectionParameters {
 public:
  SectionParameters(ParameterList& list, std::string name, S Scene::*part)
      : list_(list), name_(std::move(name)), part_(part) {}

  template <class T>
  SectionParameters& add(const char* key, T S::*field, const char* unit, Bound bound, const char* comment,
                         const char* doc);

  // An enumeration: a string naming one of `all` (as to_string spells it).
  template <class E, class = std::enable_if_t<std::is_enum_v<E>>>
  SectionParameters& add(const char* key, E S::*field, std::initializer_list<E> all, const char* comment,
                         const char* doc);

  // The key just added: a value other than its default, as TOML text (a
  // string unquoted), which the tests set to see that the key reaches its
  // member and no other.
  SectionParameters& example(const char* text);

 private:
  static const S& in(const Scene& s, S Scene::*part) {
    if constexpr (std::is_same_v<S, Scene>) return s; else return s.*part;
  }
  static S& in(Scene& s, S Scene::*part) {
    if constexpr (std::is_same_v<S, Scene>) return s; else return s.*part;
  }
  Parameter make(const char* key, ParameterKind kind, const char* unit, Bound bound, const char* comment,
                 const char* doc) const {
    return Parameter{name_, key, kind, unit, std::move(bound), {}, comment, doc, {}, {}, {}, {}};
  }

  ParameterList& list_;
  std::string name_;
  S Scene::*part_;
};

class ParameterList {
 public:
  SectionParameters<Scene> top() { return {*this, "", nullptr}; }
  template <class S>
  SectionParameters<S> section(const char* name, S Scene::*part) {
    sections_.push_back(name);
    return {*this, name, part};
  }
  void push(Parameter p) { params_.push_back(std::move(p)); }
  Parameter& back() { return params_.back(); }

  const std::vector<Parameter>& all() const { return params_; }
  const std::vector<std::string>& sections() const { return sections_; }
  const Parameter* find(const std::string& full_name) const;

 private:
  std::vector<Parameter> params_;
  std::vector<std::string> sections_;
};

template <class S>
template <class T>
SectionParameters<S>& SectionParameters<S>::add(const char* key, T S::*field, const char* unit, Bound bound,
                                                const char* comment, const char* doc) {
  Parameter p = make(key, kind_of<T>(), unit, std::move(bound), comment, doc);
  const auto part = part_;
  p.get = [part, field](const Scene& s) { return ParameterValue(in(s, part).*field); };
  p.set = [part, field](Scene& s, const ParameterValue& v) { in(s, part).*field = std::get<T>(v); };
  p.same = [part, field](const Scene& a, const Scene& b) {
    return same_bits(in(a, part).*field, in(b, part).*field);
  };
  list_.push(std::move(p));
  return *this;
}

template <class S>
template <class E, class>
SectionParameters<S>& SectionParameters<S>::add(const char* key, E S::*field, std::initializer_list<E> all,
                                                const char* comment, const char* doc) {
  Parameter p = make(key, ParameterKind::String, "", any(), comment, doc);
  for (E e : all) p.choices.push_back(to_string(e));
  const auto part = part_;
  const std::vector<E> values(all);
  p.get = [part, field](const Scene& s) { return ParameterValue(std::string(to_string(in(s, part).*field))); };
  p.set = [part, field, values](Scene& s, const ParameterValue& v) {
    for (E e : values)
      if (std::get<std::string>(v) == to_string(e)) in(s, part).*field = e;
  };
  p.same = [part, field](const Scene& a, const Scene& b) { return in(a, part).*field == in(b, part).*field; };
  list_.push(std::move(p));
  return *this;
}

template <class S>
SectionParameters<S>& SectionParameters<S>::example(const char* text) {
  list_.back().example = text;
  return *this;
}

// The scene as TOML: a header line, top-level keys, then each [section],
// "key = value  # comment" with the comments aligned.
std::string parameters_to_toml(const ParameterList& list, const Scene& s);

// The reference: a markdown table per section (key, default, unit,
// allowed values, meaning), the defaults taken from `defaults`.
std::string parameters_to_markdown(const ParameterList& list, const Scene& defaults);

}  // namespace drape
