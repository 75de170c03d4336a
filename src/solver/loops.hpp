#pragma once
// The loops that drive the kernels over an active list. The paper's scheme
// (active lists) splits the list into equal chunks, one per thread; the
// alternatives hand out whole tiles with OpenMP's static, dynamic or guided
// schedule (paper Fig. 8). Kernels write per-slot results only, so every
// schedule gives bitwise the same numbers.
#include <cstdint>

#include "amrc/active_lists.hpp"
#include "solver/scene.hpp"

namespace drape {

struct LoopPolicy {
  Schedule schedule = Schedule::ActiveLists;
  int chunk = 4;  // tiles per chunk (dynamic)
};

template <class F>
void for_each_item(const ActiveList& list, const LoopPolicy& pol, F&& f) {
  const int64_t n = list.size();
  const int nt = int(list.tile_begin.size()) - 1;
  const int64_t* items = list.items.data();
  const int64_t* tb = list.tile_begin.data();
  switch (pol.schedule) {
    case Schedule::ActiveLists:
#pragma omp parallel for schedule(static)
      for (int64_t k = 0; k < n; ++k) f(items[k]);
      break;
    case Schedule::Static:
#pragma omp parallel for schedule(static)
      for (int t = 0; t < nt; ++t)
        for (int64_t k = tb[t]; k < tb[t + 1]; ++k) f(items[k]);
      break;
    case Schedule::Dynamic:
#pragma omp parallel for schedule(dynamic, pol.chunk)
      for (int t = 0; t < nt; ++t)
        for (int64_t k = tb[t]; k < tb[t + 1]; ++k) f(items[k]);
      break;
    case Schedule::Guided:
#pragma omp parallel for schedule(guided)
      for (int t = 0; t < nt; ++t)
        for (int64_t k = tb[t]; k < tb[t + 1]; ++k) f(items[k]);
      break;
  }
}

// Per-tile sums of value(item) over each tile's run, in list order: the
// fixed-order first stage of every reduction. out[t] for owned tile t.
template <class F>
void tile_sums(const ActiveList& list, F&& value, double* out) {
  const int nt = int(list.tile_begin.size()) - 1;
#pragma omp parallel for schedule(dynamic, 1)
  for (int t = 0; t < nt; ++t) {
    double s = 0;
    for (int64_t k = list.tile_begin[t]; k < list.tile_begin[t + 1]; ++k) s += value(list.items[k]);
    out[t] = s;
  }
}

}  // namespace drape
