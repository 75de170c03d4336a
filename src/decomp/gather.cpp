#include "decomp/gather.hpp"

namespace drape {

namespace {

// Visits (value index) of every value of rank r's tiles, in tile order.
template <class F>
void each_value(const Tiling& tl, const std::vector<int>& owner, int r, int per, F&& f) {
  for (int t = 0; t < tl.count(); ++t) {
    if (owner[t] != r) continue;
    const TileRange g = tl.range(t);
    for (int i = g.i0; i < g.i1; ++i)
      for (int j = g.j0; j < g.j1; ++j)
        for (int c = 0; c < per; ++c) f((int64_t(i) * tl.nj + j) * per + c);
  }
}

}  // namespace

void gather_on_root(double* data, int per, const Tiling& tl, const std::vector<int>& owner, MPI_Comm comm) {
  int me = 0, ranks = 1;
  MPI_Comm_rank(comm, &me);
  MPI_Comm_size(comm, &ranks);
  if (ranks == 1) return;
  std::vector<double> mine;
  each_value(tl, owner, me, per, [&](int64_t k) { mine.push_back(data[k]); });
  std::vector<int> counts(ranks, 0), displs(ranks, 0);
  for (int t = 0; t < tl.count(); ++t) {
    const TileRange g = tl.range(t);
    counts[owner[t]] += (g.i1 - g.i0) * (g.j1 - g.j0) * per;
  }
  for (int r = 1; r < ranks; ++r) displs[r] = displs[r - 1] + counts[r - 1];
  std::vector<double> all(me == 0 ? size_t(displs[ranks - 1] + counts[ranks - 1]) : 0);
  MPI_Gatherv(mine.data(), int(mine.size()), MPI_DOUBLE, all.data(), counts.data(), displs.data(),
              MPI_DOUBLE, 0, comm);
  if (me != 0) return;
  for (int r = 1; r < ranks; ++r) {
    size_t u = size_t(displs[r]);
    each_value(tl, owner, r, per, [&](int64_t k) { data[k] = all[u++]; });
  }
}

}  // namespace drape
