#pragma once
// What values a scene key allows, and the words that say so: in the message
// that refuses a value and in the configuration reference.
#include <functional>
#include <string>
#include <vector>

namespace drape {

// The values a key allows, checked on each number it holds (an array's
// elements, a string's length). `text` is what messages and the reference
// say after "must be"; `note` is added in parentheses.
struct Bound {
  std::string text;                    // "> 0", "in [0, 1)"; empty: anything
  std::function<bool(double)> ok;      // null: anything
  std::string note;                    // "0: no limit"
  std::string subject;                 // arrays: "sizes" -> "sizes must be > 0"
  bool each = false;                   // "NI and NJ must each be >= 3"
  std::string message;                 // replaces the generated one ("must not be empty")

  Bound with_note(std::string n) const;
  // "must be > 0, got -1.0" when a number is outside, else "". `got` is
  // the value as the message quotes it.
  std::string refusal(const std::vector<double>& numbers, const std::string& got) const;
};

Bound any();
Bound positive();                      // > 0
Bound non_negative();                  // >= 0
Bound at_least(double lo);             // >= lo
Bound above(double lo);                // > lo
Bound in_closed(double lo, double hi); // [lo, hi]
Bound in_half_open(double lo, double hi);  // [lo, hi)
Bound zero_or(const Bound& b, const std::string& zero_means);  // 0 (zero_means) or b
Bound non_empty();                     // a string
Bound all_of(const std::string& subject, Bound b);   // an array: "sizes must be ..."
Bound each_of(const std::string& subject, Bound b);  // an array: "NI and NJ must each be ..."

}  // namespace drape
