#include "decomp/halo_exchange.hpp"

#include <algorithm>
#include <map>

namespace drape {

HaloExchange::HaloExchange(const Tiling& tl, const std::vector<int>& owner, MPI_Comm comm, int width,
                           int ring_width)
    : tiling_(tl), comm_(comm), width_(width), ring_width_(ring_width), n_(int64_t(tl.ni) * tl.nj) {
  replan(owner);
}

void HaloExchange::replan(const std::vector<int>& owner) {
  const Tiling& tl = tiling_;
  const int width = width_;
  int me = 0;
  MPI_Comm_rank(comm_, &me);
  peers_.clear();
  ring_.clear();
  ++version_;
  std::map<int, Peer> peers;
  std::vector<int> near, close;
  for (int i = 0; i < tl.ni; ++i)
    for (int j = 0; j < tl.nj; ++j) {
      // Inside a tile, away from its border, no other rank is near.
      const int ii = i % tl.t, jj = j % tl.t;
      const bool inner = ii >= width && ii < tl.t - width && jj >= width && jj < tl.t - width &&
                         i + width < tl.ni && j + width < tl.nj;
      if (inner) continue;
      const int64_t p = int64_t(i) * tl.nj + j;
      const int o = owner[tl.tile_of(i, j)];
      window_owners(tl, owner, i, j, width, near);
      if (o == me) {  // every other rank near p needs it
        for (int r : near)
          if (r != me) peers[r].send.push_back(p);
      } else if (std::find(near.begin(), near.end(), me) != near.end()) {
        peers[o].recv.push_back(p);
        window_owners(tl, owner, i, j, ring_width_, close);
        if (std::find(close.begin(), close.end(), me) != close.end()) ring_.push_back(p);
      }
    }
  for (auto& [r, peer] : peers) {
    peer.rank = r;
    peers_.push_back(std::move(peer));
  }
  sbuf_.assign(peers_.size(), {});
  rbuf_.assign(peers_.size(), {});
  for (size_t k = 0; k < peers_.size(); ++k) {  // the largest message: z's 8 values per particle
    sbuf_[k].reserve(8 * peers_[k].send.size());
    rbuf_[k].reserve(8 * peers_[k].recv.size());
  }
  req_.resize(2 * peers_.size());
}

int64_t HaloExchange::ghosts() const {
  int64_t g = 0;
  for (const Peer& p : peers_) g += int64_t(p.recv.size());
  return g;
}

void HaloExchange::exchange(double* z, int blocks) const {
  // Per particle: its 3 positions, then its 5 forces (z's blocks).
  const Field all[4] = {{0, 3}, {3 * n_, 2}, {5 * n_, 2}, {7 * n_, 1}};
  const bool pos = blocks & kPositions, forces = blocks & kForces;
  run(z, pos ? all : all + 1, (pos ? 1 : 0) + (forces ? 3 : 0));
}

void HaloExchange::exchange_particles(double* a, int per) const {
  const Field one[1] = {{0, per}};
  run(a, one, 1);
}

template <class Pack, class Unpack>
void HaloExchange::transfer(int per, Pack&& pack, Unpack&& unpack) const {
  if (peers_.empty()) return;
  const double t0 = MPI_Wtime();
  const int np = int(peers_.size());
  const int tag = 0x4a10;
  for (int k = 0; k < np; ++k) {
    rbuf_[k].resize(peers_[k].recv.size() * per);
    MPI_Irecv(rbuf_[k].data(), int(rbuf_[k].size()), MPI_DOUBLE, peers_[k].rank, tag, comm_, &req_[k]);
  }
  for (int k = 0; k < np; ++k) {
    std::vector<double>& b = sbuf_[k];
    b.resize(peers_[k].send.size() * per);
    pack(k, b.data());
    MPI_Isend(b.data(), int(b.size()), MPI_DOUBLE, peers_[k].rank, tag, comm_, &req_[np + k]);
    bytes += int64_t(b.size() * sizeof(double));
  }
  MPI_Waitall(2 * np, req_.data(), MPI_STATUSES_IGNORE);
  for (int k = 0; k < np; ++k) unpack(k, rbuf_[k].data());
  ++exchanges;
  seconds += MPI_Wtime() - t0;
}

void HaloExchange::run(double* z, const Field* fields, int nfields) const {
  int per = 0;
  for (int q = 0; q < nfields; ++q) per += fields[q].per;
  transfer(
      per,
      [&](int k, double* b) {
        for (int64_t p : peers_[k].send)
          for (int q = 0; q < nfields; ++q)
            for (int c = 0; c < fields[q].per; ++c) *b++ = z[fields[q].offset + fields[q].per * p + c];
      },
      [&](int k, const double* b) {
        for (int64_t p : peers_[k].recv)
          for (int q = 0; q < nfields; ++q)
            for (int c = 0; c < fields[q].per; ++c) z[fields[q].offset + fields[q].per * p + c] = *b++;
      });
}

void HaloExchange::plan(const std::function<void(int64_t, bool)>& f) const {
  for (const Peer& peer : peers_)
    for (int64_t p : peer.send) f(p, true);
  for (const Peer& peer : peers_)
    for (int64_t p : peer.recv) f(p, false);
}

// The plan's particles counted on across the peers, as plan() lists them.
void HaloExchange::exchange_at(double* a, const int32_t* send_at, const int32_t* recv_at) const {
  transfer(
      3,
      [&](int k, double* b) {
        const int32_t* at = send_at;
        for (int j = 0; j < k; ++j) at += peers_[j].send.size();
        for (size_t u = 0; u < peers_[k].send.size(); ++u)
          for (int c = 0; c < 3; ++c) *b++ = at[u] >= 0 ? a[3 * int64_t(at[u]) + c] : 0.0;
      },
      [&](int k, const double* b) {
        const int32_t* at = recv_at;
        for (int j = 0; j < k; ++j) at += peers_[j].recv.size();
        for (size_t u = 0; u < peers_[k].recv.size(); ++u, b += 3)
          if (at[u] >= 0)
            for (int c = 0; c < 3; ++c) a[3 * int64_t(at[u]) + c] = b[c];
      });
}

}  // namespace drape
