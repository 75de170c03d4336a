// Bounds on scene keys (bound.hpp).
#include "io/bound.hpp"

#include <algorithm>
#include <cstdio>

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

}  // namespace

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

std::string Bound::refusal(const std::vector<double>& numbers, const std::string& got) const {
  if (!ok || std::all_of(numbers.begin(), numbers.end(), ok)) return "";
  if (!message.empty()) return message;
  const std::string lead = subject.empty() ? "must be " : subject + (each ? " must each be " : " must be ");
  return lead + text + (note.empty() ? "" : " (" + note + ")") + ", got " + got;
}

}  // namespace drape
