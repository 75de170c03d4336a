#pragma once
// Halo exchange (docs/design.md §3): each rank's ghosts are the particles of other
// ranks within `width` of its own, in the max norm, so that the ring of
// elements within `ring_width` around its tiles can be computed locally. On
// the finest mesh that is 2 and 1 (a triple reads its neighbours); AMRC's
// coarse elements and hanging chains reach further (see ghost_widths). The plan
// follows from the tile owners alone, which every rank knows: each side
// lists the particles it sends or receives in ascending global id, so no
// index travels. An exchange posts every receive first, then sends one
// message per neighbour rank, then waits.
// Contact ghosts (plan_contact, for self-contact) follow the cloth, not the
// tiles: every rank's box about its free particles, inflated by the reach,
// goes to every rank; each rank sends every other the ids and positions of
// its own free particles inside that rank's box (ascending id), and the
// lists narrowed to the particles the receiver reads (keep_contact), values
// only, with every later exchange that carries positions, and with every
// exchange of per-particle arrays.
#include <mpi.h>

#include <cstdint>
#include <functional>
#include <vector>

#include "mesh/tiles.hpp"
#include "solver/halo.hpp"

namespace drape {

class HaloExchange : public Halo {
 public:
  HaloExchange(const Tiling& tiling, const std::vector<int>& owner, MPI_Comm comm, int width = 2,
               int ring_width = 1);

  // A new plan for new tile owners (after a migration), same widths.
  void replan(const std::vector<int>& owner);
  // A new plan for new widths, same owners (grid sequencing's finer stage).
  void replan(const std::vector<int>& owner, int width, int ring_width) {
    width_ = width;
    ring_width_ = ring_width;
    replan(owner);
  }

  using Halo::exchange;
  void exchange(double* z, int blocks, const Layout& layout, const int32_t* slot) const override;
  int64_t grid_particles() const override { return n_; }
  void exchange_particles(double* a, int per) const override;
  void plan_contact(const std::vector<int64_t>& own, const double* own_x, double reach,
                    std::vector<int64_t>& ghosts, std::vector<double>& ghost_x) const override;
  void keep_contact(const std::vector<int64_t>& kept) const override;
  // The tile plan's particles, then the contact plan's (sent, then received).
  void plan(const std::function<void(int64_t, bool)>& f) const override;
  uint64_t plan_version() const override { return version_; }
  void exchange_at(double* a, const int32_t* send_at, const int32_t* recv_at) const override;

  // Ghosts within ring_width of this rank's (ascending): the element ring.
  const std::vector<int64_t>& ring() const { return ring_; }
  int64_t ghosts() const;
  // The tile plan's ghosts (not the contact ones), ascending.
  std::vector<int64_t> ghost_ids() const;
  int neighbours() const { return int(peers_.size()); }
  int width() const { return width_; }
  int ring_width() const { return ring_width_; }
  // Contact ghosts on this rank (the last plan_contact's; 0 after replan).
  int64_t contact_ghosts() const;

  // Running totals over all exchanges on this rank.
  mutable double seconds = 0;
  mutable int64_t bytes = 0, exchanges = 0;

 private:
  // A run of `per` values per particle starting at `offset`, particle p's
  // at slot[p] (null: at p).
  struct Field {
    int64_t offset;
    int per;
    const int32_t* slot = nullptr;
    int64_t at(int64_t p, int c) const { return offset + per * (slot ? int64_t(slot[p]) : p) + c; }
  };
  // The tile plan's exchange of `fields`, with the contact plan's of
  // `contact` (null: none) in the same round.
  void run(double* data, const Field* fields, int nfields, const Field* contact) const;
  // One exchange of per[0] values a particle over the tile plan and, with
  // `contact`, per[1] over the contact plan in the same round: pack(i, k, b)
  // fills plan i's (0 tiles, 1 contact) peer k's send buffer, unpack(i, k, b)
  // reads its receive buffer (plans, then peers, in order).
  template <class Pack, class Unpack>
  void transfer(const int per[2], bool contact, Pack&& pack, Unpack&& unpack) const;

  struct Peer {
    int rank;
    std::vector<int64_t> send, recv;  // particle ids, ascending
  };
  // One plan's messages: receives posted, sends packed and posted (requests
  // from req), and after the wait the receives unpacked.
  struct Round {
    const std::vector<Peer>& peers;
    std::vector<std::vector<double>>& sbuf;
    std::vector<std::vector<double>>& rbuf;
    int tag;
  };
  int post_receives(const Round& r, int per, MPI_Request* req) const;
  Tiling tiling_;
  MPI_Comm comm_;
  int width_, ring_width_;
  int64_t n_ = 0;  // particles in the grid
  mutable uint64_t version_ = 0;  // changes of either plan so far
  std::vector<Peer> peers_;
  std::vector<int64_t> ring_;
  mutable std::vector<std::vector<double>> sbuf_, rbuf_;
  mutable std::vector<MPI_Request> req_;
  // The contact plan, one entry per rank (empty lists: no messages); its
  // buffers, and the boxes of the last plan (6 per rank).
  mutable std::vector<Peer> contact_;
  mutable std::vector<std::vector<double>> csbuf_, crbuf_;
  mutable std::vector<double> boxes_;
  mutable std::vector<int64_t> sorted_;
  mutable std::vector<std::vector<int64_t>> kept_in_, kept_out_;
  mutable int64_t contact_sends_ = 0;  // particles this rank sends in the contact plan
  void clear_contact() const;
};

}  // namespace drape
