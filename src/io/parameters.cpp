// The schema's mechanism (parameters.hpp): bounds and their messages, the
// TOML text of a value, lookup by name.
#include "io/parameters.hpp"

#include <algorithm>
#include <cstdio>

#include "io/toml_text.hpp"

namespace drape {
namespace {

// A bound's number as the user would write it: 1, 0.5, 1024.
std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

Bound bound(std::string text, std::function<bool(double)> ok) {
  Bound b;
  b.text = std::move(text);
  b.ok = std::move(ok);
  return b;
}

// The numbers a bound is checked on: the value, an array's elements, a
// string's length; none for a boolean.
struct Numbers {
  std::vector<double> operator()(int x) const { return {double(x)}; }
  std::vector<double> operator()(double x) const { return {x}; }
  std::vector<double> operator()(bool) const { return {}; }
  std::vector<double> operator()(const std::string& x) const { return {double(x.size())}; }
  template <class T, size_t N>
  std::vector<double> operator()(const std::array<T, N>& a) const { return {a.begin(), a.end()}; }
};

std::vector<double> numbers(const ParameterValue& v) { return std::visit(Numbers{}, v); }

struct Text {
  std::string operator()(int x) const { return std::to_string(x); }
  std::string operator()(double x) const { return format_double(x); }
  std::string operator()(bool x) const { return x ? "true" : "false"; }
  std::string operator()(const std::string& x) const { return quote(x); }
  template <class T, size_t N>
  std::string operator()(const std::array<T, N>& a) const { return format_array(a); }
};

}  // namespace

const char* expected_text(ParameterKind k) {
  switch (k) {
    case ParameterKind::Int: return "an integer";
    case ParameterKind::Float: return "a number";
    case ParameterKind::Bool: return "a boolean (true or false)";
    case ParameterKind::String: return "a string";
    case ParameterKind::Int2: return "an array of 2 integers";
    case ParameterKind::Float2: return "an array of 2 numbers";
    case ParameterKind::Float3: return "an array of 3 numbers";
  }
  return "?";
}

Bound Bound::with_note(std::string n) const {
  Bound b = *this;
  b.note = std::move(n);
  return b;
}

Bound any() { return {}; }
Bound positive() { return bound("> 0", [](double v) { return v > 0; }); }
Bound non_negative() { return bound(">= 0", [](double v) { return v >= 0; }); }
Bound at_least(double lo) { return bound(">= " + number(lo), [lo](double v) { return v >= lo; }); }

Bound above(double lo) { return bound("> " + number(lo), [lo](double v) { return v > lo; }); }

Bound in_closed(double lo, double hi) {
  return bound("in [" + number(lo) + ", " + number(hi) + "]", [lo, hi](double v) { return v >= lo && v <= hi; });
}

Bound in_half_open(double lo, double hi) {
  return bound("in [" + number(lo) + ", " + number(hi) + ")", [lo, hi](double v) { return v >= lo && v < hi; });
}

Bound zero_or(const Bound& b, const std::string& zero_means) {
  const auto ok = b.ok;
  return bound("0 (" + zero_means + ") or " + b.text, [ok](double v) { return v == 0 || ok(v); });
}

Bound non_empty() {
  Bound b = bound("not empty", [](double length) { return length > 0; });
  b.message = "must not be empty";
  return b;
}

Bound all_of(const std::string& subject, Bound b) {
  b.subject = subject;
  return b;
}

Bound each_of(const std::string& subject, Bound b) {
  b.subject = subject;
  b.each = true;
  return b;
}

std::string Parameter::refusal(const ParameterValue& v) const {
  if (!bound.ok) return "";
  const std::vector<double> xs = numbers(v);
  if (std::all_of(xs.begin(), xs.end(), bound.ok)) return "";
  if (!bound.message.empty()) return bound.message;
  const std::string lead =
      bound.subject.empty() ? "must be " : bound.subject + (bound.each ? " must each be " : " must be ");
  const std::string note = bound.note.empty() ? "" : " (" + bound.note + ")";
  return lead + bound.text + note + ", got " + value_text(v);
}

std::string value_text(const ParameterValue& v) { return std::visit(Text{}, v); }

const Parameter* ParameterList::find(const std::string& full_name) const {
  for (const Parameter& p : params_)
    if (p.full_name() == full_name) return &p;
  return nullptr;
}

}  // namespace drape
