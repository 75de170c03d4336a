#pragma once
// What a run's large arrays hold, owner by owner: each owner lists its
// arrays' capacities here, so that a test can bound the bytes a particle
// costs and the memory figures name the arrays (docs/performance.md).
#include <cstddef>
#include <string>
#include <vector>

namespace drape {

struct Cloth;
struct ActiveLists;

struct MemoryTable {
  struct Row {
    std::string owner, array;
    size_t bytes = 0;
  };
  std::vector<Row> rows;

  template <class T>
  void add(const char* owner, const char* array, const std::vector<T>& v) {
    rows.push_back({owner, array, v.capacity() * sizeof(T)});
  }
  void add(const char* owner, const char* array, size_t bytes) { rows.push_back({owner, array, bytes}); }
  size_t total() const {
    size_t s = 0;
    for (const Row& r : rows) s += r.bytes;
    return s;
  }
};

// The cloth's arrays and the active lists' (items and runs).
void add_memory(MemoryTable& t, const Cloth& c);
void add_memory(MemoryTable& t, const ActiveLists& l);

}  // namespace drape
