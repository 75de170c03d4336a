// The schema's mechanism (parameters.hpp): a value's numbers and TOML
// text, lookup by name.
#include "io/parameters.hpp"

#include "io/toml_text.hpp"

namespace drape {
namespace {

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

std::string Parameter::refusal(const ParameterValue& v) const {
  return bound.ok ? bound.refusal(numbers(v), value_text(v)) : "";
}

std::string Parameter::example_toml() const { return kind == ParameterKind::String ? quote(example) : example; }

std::string value_text(const ParameterValue& v) { return std::visit(Text{}, v); }

const Parameter* ParameterList::find(const std::string& full_name) const {
  for (const Parameter& p : params_)
    if (p.full_name() == full_name) return &p;
  return nullptr;
}

}  // namespace drape
