#pragma once
// A minimal JSON writer for run reports: objects, arrays, numbers, strings.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace drape {

class Json {
 public:
  Json& begin_object(const char* key = nullptr) { return open(key, '{'); }
  Json& end_object() { return close('}'); }
  Json& begin_array(const char* key = nullptr) { return open(key, '['); }
  Json& end_array() { return close(']'); }
  Json& value(const char* key, double v) {
    char b[32];
    if (std::isfinite(v)) std::snprintf(b, sizeof b, "%.17g", v);
    else std::snprintf(b, sizeof b, "null");
    return raw(key, b);
  }
  Json& value(const char* key, long long v) { return raw(key, std::to_string(v)); }
  Json& value(const char* key, int v) { return value(key, (long long)v); }
  Json& value(const char* key, bool v) { return raw(key, v ? "true" : "false"); }
  Json& value(const char* key, const std::string& v) { return raw(key, quote(v)); }
  Json& value(const char* key, const char* v) { return raw(key, quote(v)); }
  const std::string& str() const { return out_; }

  static std::string quote(const std::string& s) {
    std::string q = "\"";
    for (unsigned char c : s) {
      if (c == '"' || c == '\\') q += '\\', q += char(c);
      else if (c == '\n') q += "\\n";
      else if (c < 0x20) {
        char b[8];
        std::snprintf(b, sizeof b, "\\u%04x", c);
        q += b;
      } else q += char(c);
    }
    return q + "\"";
  }

 private:
  Json& raw(const char* key, const std::string& v) {
    sep(key);
    out_ += v;
    return *this;
  }
  Json& open(const char* key, char c) {
    sep(key);
    out_ += c;
    first_.push_back(true);
    return *this;
  }
  Json& close(char c) {
    first_.pop_back();
    out_ += '\n' + std::string(2 * first_.size(), ' ') + c;
    return *this;
  }
  void sep(const char* key) {
    if (!first_.empty()) {
      if (!first_.back()) out_ += ',';
      first_.back() = false;
      out_ += '\n' + std::string(2 * first_.size(), ' ');
    }
    if (key) out_ += quote(key) + ": ";
  }
  std::string out_;
  std::vector<bool> first_;
};

}  // namespace drape
