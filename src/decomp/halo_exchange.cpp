#include "decomp/halo_exchange.hpp"

#include <algorithm>
#include <iterator>
#include <limits>
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
  clear_contact();  // a particle it lists may have moved to another rank
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

std::vector<int64_t> HaloExchange::ghost_ids() const {
  std::vector<int64_t> ids;
  for (const Peer& p : peers_) ids.insert(ids.end(), p.recv.begin(), p.recv.end());
  std::sort(ids.begin(), ids.end());
  return ids;
}

void HaloExchange::exchange(double* z, int blocks, const Layout& L, const int32_t* slot) const {
  // Per particle: its 3 positions, then its 5 forces (z's blocks, in slots).
  const Field all[4] = {{0, 3}, {L.tension(), 2, slot}, {L.moment(), 2, slot}, {L.shear(), 1, slot}};
  const bool pos = blocks & kPositions, forces = blocks & kForces;
  // Contact ghosts are read for their positions only.
  run(z, pos ? all : all + 1, (pos ? 1 : 0) + (forces ? 3 : 0), pos ? all : nullptr);
}

void HaloExchange::exchange_particles(double* a, int per) const {
  const Field one[1] = {{0, per}};
  run(a, one, 1, one);
}

int HaloExchange::post_receives(const Round& r, int per, MPI_Request* req) const {
  int posted = 0;
  for (size_t k = 0; k < r.peers.size(); ++k) {
    if (r.peers[k].recv.empty()) continue;
    std::vector<double>& b = r.rbuf[k];
    b.resize(r.peers[k].recv.size() * per);
    MPI_Irecv(b.data(), int(b.size()), MPI_DOUBLE, r.peers[k].rank, r.tag, comm_, &req[posted++]);
  }
  return posted;
}

// A peer with nothing to send or receive in a plan gets no message: both
// sides' lists follow from the same owners (or, for contact, the counts
// both sides hold), so the other side posts none either.
template <class Pack, class Unpack>
void HaloExchange::transfer(const int per[2], bool contact, Pack&& pack, Unpack&& unpack) const {
  const bool touch = contact && contact_ghosts() + contact_sends_ > 0;
  if (peers_.empty() && !touch) return;
  const double t0 = MPI_Wtime();
  const Round rounds[2] = {{peers_, sbuf_, rbuf_, 0x4a10}, {contact_, csbuf_, crbuf_, 0x4a12}};
  const int nr = touch ? 2 : 1;
  req_.resize(2 * (peers_.size() + contact_.size()));
  int posted = 0;
  for (int i = 0; i < nr; ++i) posted += post_receives(rounds[i], per[i], req_.data() + posted);
  for (int i = 0; i < nr; ++i) {
    const Round& r = rounds[i];
    for (size_t k = 0; k < r.peers.size(); ++k) {
      if (r.peers[k].send.empty()) continue;
      std::vector<double>& b = r.sbuf[k];
      b.resize(r.peers[k].send.size() * per[i]);
      pack(i, k, b.data());
      MPI_Isend(b.data(), int(b.size()), MPI_DOUBLE, r.peers[k].rank, r.tag, comm_, &req_[posted++]);
      bytes += int64_t(b.size() * sizeof(double));
    }
  }
  MPI_Waitall(posted, req_.data(), MPI_STATUSES_IGNORE);
  for (int i = 0; i < nr; ++i)
    for (size_t k = 0; k < rounds[i].peers.size(); ++k)
      if (!rounds[i].peers[k].recv.empty()) unpack(i, k, rounds[i].rbuf[k].data());
  ++exchanges;
  seconds += MPI_Wtime() - t0;
}

void HaloExchange::run(double* z, const Field* fields, int nfields, const Field* contact) const {
  const Field* fs[2] = {fields, contact};
  const int nf[2] = {nfields, 1};
  int per[2] = {0, contact ? contact->per : 0};
  for (int q = 0; q < nfields; ++q) per[0] += fields[q].per;
  const std::vector<Peer>* plans[2] = {&peers_, &contact_};
  transfer(
      per, contact != nullptr,
      [&](int i, size_t k, double* b) {
        for (int64_t p : (*plans[i])[k].send)
          for (int q = 0; q < nf[i]; ++q)
            for (int c = 0; c < fs[i][q].per; ++c) *b++ = z[fs[i][q].at(p, c)];
      },
      [&](int i, size_t k, const double* b) {
        for (int64_t p : (*plans[i])[k].recv)
          for (int q = 0; q < nf[i]; ++q)
            for (int c = 0; c < fs[i][q].per; ++c) z[fs[i][q].at(p, c)] = *b++;
      });
}

void HaloExchange::plan(const std::function<void(int64_t, bool)>& f) const {
  const std::vector<Peer>* plans[2] = {&peers_, &contact_};
  for (const std::vector<Peer>* ps : plans)
    for (const Peer& peer : *ps)
      for (int64_t p : peer.send) f(p, true);
  for (const std::vector<Peer>* ps : plans)
    for (const Peer& peer : *ps)
      for (int64_t p : peer.recv) f(p, false);
}

// The plan's particles counted on across the plans and peers, as plan()
// lists them: plan i's peer k starts after every earlier one's.
void HaloExchange::exchange_at(double* a, const int32_t* send_at, const int32_t* recv_at) const {
  const std::vector<Peer>* plans[2] = {&peers_, &contact_};
  auto start = [&](int i, size_t k, const int32_t* at, bool send) {
    for (int j = 0; j <= i; ++j)
      for (size_t u = 0; u < (j < i ? plans[j]->size() : k); ++u)
        at += send ? (*plans[j])[u].send.size() : (*plans[j])[u].recv.size();
    return at;
  };
  const int per[2] = {3, 3};
  transfer(
      per, true,
      [&](int i, size_t k, double* b) {
        const int32_t* at = start(i, k, send_at, true);
        for (size_t u = 0; u < (*plans[i])[k].send.size(); ++u)
          for (int c = 0; c < 3; ++c) *b++ = at[u] >= 0 ? a[3 * int64_t(at[u]) + c] : 0.0;
      },
      [&](int i, size_t k, const double* b) {
        const int32_t* at = start(i, k, recv_at, false);
        for (size_t u = 0; u < (*plans[i])[k].recv.size(); ++u, b += 3)
          if (at[u] >= 0)
            for (int c = 0; c < 3; ++c) a[3 * int64_t(at[u]) + c] = b[c];
      });
}

int64_t HaloExchange::contact_ghosts() const {
  int64_t g = 0;
  for (const Peer& p : contact_) g += int64_t(p.recv.size());
  return g;
}

void HaloExchange::clear_contact() const {
  for (Peer& p : contact_) p.send.clear(), p.recv.clear();
  contact_sends_ = 0;
  ++version_;  // plan() lists the contact plan too
}

void HaloExchange::plan_contact(const std::vector<int64_t>& own, const double* own_x, double reach,
                                std::vector<int64_t>& ghosts, std::vector<double>& ghost_x) const {
  const double t0 = MPI_Wtime();
  int me = 0, size = 1;
  MPI_Comm_rank(comm_, &me);
  MPI_Comm_size(comm_, &size);
  // This rank's box about its free particles, inflated by the reach (none: empty).
  const double inf = std::numeric_limits<double>::infinity();
  double box[6] = {inf, inf, inf, -inf, -inf, -inf};
  for (size_t k = 0; k < own.size(); ++k)
    for (int i = 0; i < 3; ++i) {
      box[i] = std::min(box[i], own_x[3 * k + i]);
      box[3 + i] = std::max(box[3 + i], own_x[3 * k + i]);
    }
  for (int i = 0; i < 3; ++i) box[i] -= reach, box[3 + i] += reach;
  boxes_.resize(6 * size_t(size));
  MPI_Allgather(box, 6, MPI_DOUBLE, boxes_.data(), 6, MPI_DOUBLE, comm_);
  // Each other rank gets this rank's particles inside its box, ascending
  // (sorted_: their places in own, by id).
  sorted_.resize(own.size());
  for (size_t k = 0; k < own.size(); ++k) sorted_[k] = int64_t(k);
  std::sort(sorted_.begin(), sorted_.end(), [&](int64_t a, int64_t b) { return own[size_t(a)] < own[size_t(b)]; });
  std::vector<int64_t> sent_at;  // per contact send, its place in own (the positions' message)
  contact_.resize(size_t(size));
  clear_contact();
  std::vector<int> nsend(size_t(size), 0), nrecv(size_t(size), 0);
  for (int r = 0; r < size; ++r) {
    Peer& peer = contact_[size_t(r)];
    peer.rank = r;
    if (r == me) continue;
    const double* b = &boxes_[6 * size_t(r)];
    for (int64_t k : sorted_) {
      const double* xp = own_x + 3 * k;
      bool inside = true;
      for (int i = 0; i < 3; ++i) inside = inside && xp[i] >= b[i] && xp[i] <= b[3 + i];
      if (inside) peer.send.push_back(own[size_t(k)]), sent_at.push_back(k);
    }
    nsend[size_t(r)] = int(peer.send.size());
    contact_sends_ += int64_t(peer.send.size());
  }
  MPI_Alltoall(nsend.data(), 1, MPI_INT, nrecv.data(), 1, MPI_INT, comm_);
  for (int r = 0; r < size; ++r) contact_[size_t(r)].recv.resize(size_t(nrecv[size_t(r)]));
  // The first message: each particle's id, then its position (ids below 2^53 travel exactly as doubles).
  csbuf_.resize(size_t(size));
  crbuf_.resize(size_t(size));
  req_.resize(2 * (peers_.size() + contact_.size()));
  const Round near{contact_, csbuf_, crbuf_, 0x4a11};
  int posted = post_receives(near, 4, req_.data());
  size_t at = 0;
  for (int r = 0; r < size; ++r) {
    std::vector<double>& b = csbuf_[size_t(r)];
    b.clear();
    for (int64_t p : contact_[size_t(r)].send) {
      b.push_back(double(p));
      for (int i = 0; i < 3; ++i) b.push_back(own_x[3 * sent_at[at] + i]);
      ++at;
    }
    if (b.empty()) continue;
    MPI_Isend(b.data(), int(b.size()), MPI_DOUBLE, r, near.tag, comm_, &req_[posted++]);
    bytes += int64_t(b.size() * sizeof(double));
  }
  MPI_Waitall(posted, req_.data(), MPI_STATUSES_IGNORE);
  // The ghosts ascending, each with its position (ids are unique: each
  // particle is free on one rank).
  std::vector<std::pair<int64_t, const double*>> got;
  for (int r = 0; r < size; ++r) {
    Peer& peer = contact_[size_t(r)];
    const std::vector<double>& b = crbuf_[size_t(r)];
    for (size_t k = 0; k < peer.recv.size(); ++k) {
      const int64_t p = int64_t(b[4 * k]);
      peer.recv[k] = p;
      got.emplace_back(p, &b[4 * k + 1]);
    }
  }
  std::sort(got.begin(), got.end());
  ghosts.resize(got.size());
  ghost_x.resize(3 * got.size());
  for (size_t k = 0; k < got.size(); ++k) {
    ghosts[k] = got[k].first;
    for (int i = 0; i < 3; ++i) ghost_x[3 * k + i] = got[k].second[i];
  }
  seconds += MPI_Wtime() - t0;
}

void HaloExchange::keep_contact(const std::vector<int64_t>& kept) const {
  const double t0 = MPI_Wtime();
  const int size = int(contact_.size());
  if (size == 0) return;  // never planned (every rank alike)
  // Each peer's received ids that are kept (both ascending); the peer sends those only.
  kept_in_.resize(size_t(size));
  kept_out_.resize(size_t(size));
  std::vector<int> nkeep(size_t(size), 0), nsend(size_t(size), 0);
  for (int r = 0; r < size; ++r) {
    std::vector<int64_t>& k = kept_out_[size_t(r)];
    k.clear();
    std::set_intersection(contact_[size_t(r)].recv.begin(), contact_[size_t(r)].recv.end(), kept.begin(), kept.end(),
                          std::back_inserter(k));
    nkeep[size_t(r)] = int(k.size());
  }
  MPI_Alltoall(nkeep.data(), 1, MPI_INT, nsend.data(), 1, MPI_INT, comm_);
  req_.resize(2 * (peers_.size() + contact_.size()));
  int posted = 0;
  const int tag = 0x4a13;
  for (int r = 0; r < size; ++r) {
    kept_in_[size_t(r)].resize(size_t(nsend[size_t(r)]));
    if (nsend[size_t(r)] > 0)
      MPI_Irecv(kept_in_[size_t(r)].data(), nsend[size_t(r)], MPI_INT64_T, r, tag, comm_, &req_[posted++]);
  }
  for (int r = 0; r < size; ++r)
    if (nkeep[size_t(r)] > 0)
      MPI_Isend(kept_out_[size_t(r)].data(), nkeep[size_t(r)], MPI_INT64_T, r, tag, comm_, &req_[posted++]);
  MPI_Waitall(posted, req_.data(), MPI_STATUSES_IGNORE);
  contact_sends_ = 0;
  for (int r = 0; r < size; ++r) {
    Peer& peer = contact_[size_t(r)];
    peer.recv.assign(kept_out_[size_t(r)].begin(), kept_out_[size_t(r)].end());
    peer.send.assign(kept_in_[size_t(r)].begin(), kept_in_[size_t(r)].end());
    contact_sends_ += int64_t(peer.send.size());
  }
  ++version_;
  seconds += MPI_Wtime() - t0;
}

}  // namespace drape
