// Small text helpers shared by the TOML readers (scene config, KES fabrics),
// so their messages name types and places the same way.
#pragma once

#include <toml++/toml.h>

#include <string>

namespace drape {

// `s` without leading and trailing blanks (space, tab, and the CR of a CRLF line).
inline std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

// What a TOML value is, for "expected X, got <type_name>" messages.
inline const char* type_name(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a floating-point number";
    case toml::node_type::boolean: return "a boolean";
    case toml::node_type::date: return "a date";
    case toml::node_type::time: return "a time";
    case toml::node_type::date_time: return "a date-time";
    default: return "nothing";
  }
}

// "file:line", or just "file" when the line is unknown (0).
inline std::string location(const std::string& file, int line) {
  return line > 0 ? file + ":" + std::to_string(line) : file;
}

// Where a parsed TOML value stands: "file:line", or "" for a value that
// came from no file.
inline std::string location(const toml::source_region& src) {
  return src.path ? location(*src.path, static_cast<int>(src.begin.line)) : "";
}

inline int line_of(const toml::node& n) { return static_cast<int>(n.source().begin.line); }
inline int line_of(const toml::key& k) { return static_cast<int>(k.source().begin.line); }

}  // namespace drape
