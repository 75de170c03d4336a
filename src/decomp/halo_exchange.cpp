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

void HaloExchange::run(double* z, const Field* fields, int nfields) const {
  if (peers_.empty()) return;
  const double t0 = MPI_Wtime();
  int per = 0;
  for (int q = 0; q < nfields; ++q) per += fields[q].per;
  const int np = int(peers_.size());
  const int tag = 0x4a10;
  for (int k = 0; k < np; ++k) {
    rbuf_[k].resize(peers_[k].recv.size() * per);
    MPI_Irecv(rbuf_[k].data(), int(rbuf_[k].size()), MPI_DOUBLE, peers_[k].rank, tag, comm_, &req_[k]);
  }
  for (int k = 0; k < np; ++k) {
    std::vector<double>& b = sbuf_[k];
    b.resize(peers_[k].send.size() * per);
    size_t u = 0;
    for (int64_t p : peers_[k].send)
      for (int q = 0; q < nfields; ++q)
        for (int c = 0; c < fields[q].per; ++c) b[u++] = z[fields[q].offset + fields[q].per * p + c];
    MPI_Isend(b.data(), int(b.size()), MPI_DOUBLE, peers_[k].rank, tag, comm_, &req_[np + k]);
    bytes += int64_t(b.size() * sizeof(double));
  }
  MPI_Waitall(2 * np, req_.data(), MPI_STATUSES_IGNORE);
  for (int k = 0; k < np; ++k) {
    size_t u = 0;
    for (int64_t p : peers_[k].recv)
      for (int q = 0; q < nfields; ++q)
        for (int c = 0; c < fields[q].per; ++c) z[fields[q].offset + fields[q].per * p + c] = rbuf_[k][u++];
  }
  ++exchanges;
  seconds += MPI_Wtime() - t0;
}

}  // namespace drape
