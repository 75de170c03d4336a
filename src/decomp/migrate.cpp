#include "decomp/migrate.hpp"

#include <algorithm>
#include <map>

namespace drape {

namespace {

constexpr int kPerParticle = 16;  // z: 3 + 2 + 2 + 1, x1: 3, x2: 3, flags, level

// Visits every value slot of tile t's particles in the fixed message order.
template <class F>
void each_value(Cloth& c, const Tiling& tl, int t, F&& f) {
  const TileRange r = tl.range(t);
  for (int i = r.i0; i < r.i1; ++i)
    for (int j = r.j0; j < r.j1; ++j) {
      const int64_t p = c.grid.id(i, j);
      for (int k = 0; k < 3; ++k) f(c.z[3 * p + k]);
      for (int k = 0; k < 2; ++k) f(c.force(0, 2 * p + k));
      for (int k = 0; k < 2; ++k) f(c.force(1, 2 * p + k));
      f(c.force(2, p));
      for (int k = 0; k < 3; ++k) f(c.x1_at(p)[k]);
      for (int k = 0; k < 3; ++k) f(c.x2_at(p)[k]);
      double fl = c.flags[p], lv = c.level[p];  // small integers: exact as doubles
      f(fl);
      f(lv);
      c.flags[p] = uint8_t(fl);
      c.level[p] = uint8_t(lv);
    }
}

// Room in x1, x2 and the forces for the arriving tiles' particles beside those held
// already (the rebalance narrows it to the new tiles and ghosts after).
void hold_arriving(Cloth& c, const Tiling& tl, const std::map<int, std::vector<int>>& in) {
  if (c.slot_of.empty() || in.empty()) return;  // every particle held
  std::vector<int> arriving;
  for (const auto& [peer, tiles] : in) arriving.insert(arriving.end(), tiles.begin(), tiles.end());
  hold_with_tiles(c, held_particles(c), tl, arriving);
}

int64_t tile_particles(const Tiling& tl, int t) {
  const TileRange r = tl.range(t);
  return int64_t(r.i1 - r.i0) * (r.j1 - r.j0);
}

}  // namespace

std::vector<int> relabel_to_overlap(const std::vector<int>& old_owner, const std::vector<int>& fresh,
                                    const std::vector<int64_t>& work, int ranks) {
  std::vector<std::vector<int64_t>> overlap(ranks, std::vector<int64_t>(ranks, 0));
  for (size_t t = 0; t < fresh.size(); ++t) overlap[fresh[t]][old_owner[t]] += work[t];
  std::vector<int> name(ranks, -1);
  std::vector<bool> taken(ranks, false);
  for (int round = 0; round < ranks; ++round) {
    int bp = -1, br = -1;
    int64_t best = -1;
    for (int p = 0; p < ranks; ++p)
      for (int r = 0; r < ranks; ++r)
        if (name[p] < 0 && !taken[r] && overlap[p][r] > best) {
          best = overlap[p][r];
          bp = p;
          br = r;
        }
    name[bp] = br;
    taken[br] = true;
  }
  std::vector<int> out(fresh.size());
  for (size_t t = 0; t < fresh.size(); ++t) out[t] = name[fresh[t]];
  return out;
}

int64_t tile_migration_bytes(const Tiling& tl, int t) {
  return tile_particles(tl, t) * kPerParticle * int64_t(sizeof(double));
}

MigrationStats migrate_tiles(Cloth& c, const Tiling& tl, const std::vector<int>& old_owner,
                             const std::vector<int>& new_owner, MPI_Comm comm) {
  int me = 0;
  MPI_Comm_rank(comm, &me);
  // Tiles by peer, ascending (map and loop order keep both sides in step).
  std::map<int, std::vector<int>> out, in;
  MigrationStats st;
  for (int t = 0; t < tl.count(); ++t) {
    if (old_owner[t] == new_owner[t]) continue;
    ++st.tiles_moved;
    st.bytes += tile_migration_bytes(tl, t);
    if (old_owner[t] == me) out[new_owner[t]].push_back(t);
    if (new_owner[t] == me) in[old_owner[t]].push_back(t);
  }
  std::vector<std::vector<double>> rbuf, sbuf;
  std::vector<MPI_Request> req;
  rbuf.reserve(in.size());
  sbuf.reserve(out.size());
  req.reserve(in.size() + out.size());
  const int tag = 0x6d16;
  for (auto& [peer, tiles] : in) {
    int64_t count = 0;
    for (int t : tiles) count += tile_particles(tl, t) * kPerParticle;
    rbuf.emplace_back(count);
    req.emplace_back();
    MPI_Irecv(rbuf.back().data(), int(count), MPI_DOUBLE, peer, tag, comm, &req.back());
  }
  for (auto& [peer, tiles] : out) {
    std::vector<double> b;
    for (int t : tiles) each_value(c, tl, t, [&](double& v) { b.push_back(v); });
    sbuf.push_back(std::move(b));
    req.emplace_back();
    MPI_Isend(sbuf.back().data(), int(sbuf.back().size()), MPI_DOUBLE, peer, tag, comm, &req.back());
  }
  MPI_Waitall(int(req.size()), req.data(), MPI_STATUSES_IGNORE);
  hold_arriving(c, tl, in);
  size_t k = 0;
  for (auto& [peer, tiles] : in) {
    size_t u = 0;
    for (int t : tiles) each_value(c, tl, t, [&](double& v) { v = rbuf[k][u++]; });
    ++k;
  }
  return st;
}

}  // namespace drape
