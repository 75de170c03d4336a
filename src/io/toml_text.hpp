#pragma once
// Values written as TOML text: what --dry-run prints, what the scene's
// messages quote, and what the configuration reference gives as defaults,
// all spelled alike.
#include <array>
#include <cstddef>
#include <string>
#include <type_traits>

namespace drape {

// Shortest text that reads back to exactly `v`, always a TOML float.
std::string format_double(double v);

// A TOML basic string: quotes, backslashes and control characters escaped.
std::string quote(const std::string& text);

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

}  // namespace drape
