#pragma once
// Splits one fuzzer input into a main text and the lines after a marker
// line, so that a single byte string can drive a parser that takes a file
// and a few extra pieces (--set overrides, a curve file).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace drape::fuzz {

struct Parts {
  std::string head;               // before the marker line
  std::string tail;               // after it ("" when there is none)
};

// The marker is a line holding exactly `marker` (e.g. "%%").
inline Parts split_at_marker(const uint8_t* data, size_t size, const std::string& marker) {
  const std::string all(reinterpret_cast<const char*>(data), size);
  const std::string line = "\n" + marker + "\n";
  const size_t at = all.find(line);
  if (at == std::string::npos) return {all, ""};
  return {all.substr(0, at + 1), all.substr(at + line.size())};
}

// At most `max` lines of `text`, each without its newline.
inline std::vector<std::string> lines_of(const std::string& text, size_t max) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start < text.size() && out.size() < max) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    out.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return out;
}

}  // namespace drape::fuzz
