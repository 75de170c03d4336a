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

std::vector<double> gather_listed_on_root(const double* data, int per, const std::vector<int64_t>& listed,
                                          const Tiling& tl, const std::vector<int>& owner, MPI_Comm comm) {
  int me = 0, ranks = 1;
  MPI_Comm_rank(comm, &me);
  MPI_Comm_size(comm, &ranks);
  auto from = [&](int64_t p) { return owner[tl.tile_of(p)]; };
  std::vector<double> mine;
  std::vector<int> counts(ranks, 0), displs(ranks, 0);
  for (int64_t p : listed) {
    counts[from(p)] += per;
    if (from(p) == me)
      for (int c = 0; c < per; ++c) mine.push_back(data[p * per + c]);
  }
  for (int r = 1; r < ranks; ++r) displs[r] = displs[r - 1] + counts[r - 1];
  std::vector<double> all(me == 0 ? listed.size() * per : 0);
  MPI_Gatherv(mine.data(), int(mine.size()), MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, 0,
              comm);
  if (me != 0) return {};
  // Each rank's values arrive in listed's order: deal them back in place.
  std::vector<double> out(all.size());
  std::vector<int> next(displs);
  for (size_t k = 0; k < listed.size(); ++k) {
    int& u = next[from(listed[k])];
    for (int c = 0; c < per; ++c) out[k * per + c] = all[u++];
  }
  return out;
}

void or_on_root(std::vector<uint8_t>& bytes, MPI_Comm comm) {
  int me = 0;
  MPI_Comm_rank(comm, &me);
  MPI_Reduce(me == 0 ? MPI_IN_PLACE : bytes.data(), bytes.data(), int(bytes.size()), MPI_BYTE, MPI_BOR, 0, comm);
}

}  // namespace drape
