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
#include <mpi.h>

#include <cstdint>
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

  void exchange(double* z, int blocks) const override;
  void exchange_particles(double* a, int per) const override;
  void plan(const std::function<void(int64_t, bool)>& f) const override;
  uint64_t plan_version() const override { return version_; }
  void exchange_at(double* a, const int32_t* send_at, const int32_t* recv_at) const override;

  // Ghosts within ring_width of this rank's (ascending): the element ring.
  const std::vector<int64_t>& ring() const { return ring_; }
  int64_t ghosts() const;
  int neighbours() const { return int(peers_.size()); }

  // Running totals over all exchanges on this rank.
  mutable double seconds = 0;
  mutable int64_t bytes = 0, exchanges = 0;

 private:
  // A run of `per` values per particle starting at `offset`.
  struct Field {
    int64_t offset;
    int per;
  };
  void run(double* data, const Field* fields, int nfields) const;
  // One exchange of `per` values a particle: pack(k, b) fills peer k's
  // send buffer, unpack(k, b) reads its receive buffer (peers in order).
  template <class Pack, class Unpack>
  void transfer(int per, Pack&& pack, Unpack&& unpack) const;

  struct Peer {
    int rank;
    std::vector<int64_t> send, recv;  // particle ids, ascending
  };
  Tiling tiling_;
  MPI_Comm comm_;
  int width_, ring_width_;
  int64_t n_ = 0;  // particles in the grid
  uint64_t version_ = 0;  // replans so far
  std::vector<Peer> peers_;
  std::vector<int64_t> ring_;
  mutable std::vector<std::vector<double>> sbuf_, rbuf_;
  mutable std::vector<MPI_Request> req_;
};

}  // namespace drape
