#pragma once
// The sizing rule of the arrays that hold a rank's listed elements, rows or
// unknowns (docs/development.md, "No allocation while stepping").
#include <algorithm>
#include <cstddef>
#include <vector>

namespace drape {

// v holds `need` entries, `fill` where new: capacity grows where need
// exceeds it, with an eighth to spare (but never past `most`, the grid's
// count: an AMRC mesh refines some leaves at a time) or, with `exact`, is
// need (shrinks too). A new capacity takes a new array: the contents are
// rewritten before they are read, none is copied.
template <class T>
void fit(std::vector<T>& v, size_t need, size_t most, bool exact, const T& fill) {
  if (exact ? v.capacity() != need : v.capacity() < need) {
    std::vector<T> fresh;
    fresh.reserve(exact ? need : std::max(need, std::min(most, need + need / 8)));
    v.swap(fresh);
  }
  v.resize(need, fill);  // within the capacity: no allocation
}

// The same, keeping the contents (the first `need` entries) across a new
// capacity: for what the lists' positions hold from one call to the next.
template <class T>
void fit_keeping(std::vector<T>& v, size_t need, size_t most, bool exact, const T& fill) {
  if (exact ? v.capacity() != need : v.capacity() < need) {
    std::vector<T> fresh;
    fresh.reserve(exact ? need : std::max(need, std::min(most, need + need / 8)));
    fresh.assign(v.begin(), v.begin() + std::min(v.size(), need));
    v.swap(fresh);
  }
  v.resize(need, fill);
}

}  // namespace drape
