// TOML value text (see toml_text.hpp).
#include "io/toml_text.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>

namespace drape {

// Like Python's repr: plain digits for 1e-4 <= |v| < 1e16, else an exponent.
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

}  // namespace drape
