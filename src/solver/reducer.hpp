#pragma once
// Global sums in a fixed order (docs/design.md §3): each rank hands in one partial per
// owned tile; the result is the sum over all tiles in tile order, bitwise the
// same for any number of ranks and threads. The MPI version lives in
// src/decomp/; physics only sees this interface.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace drape {

class Reducer {
 public:
  virtual ~Reducer() = default;
  // partials: k rows, each with one value per owned tile (ascending tile id).
  // out[r] = sum over all tiles (all ranks) of row r, in tile order.
  virtual void sum_tiles(const std::vector<int>& owned_tiles, const double* partials, int k,
                         double* out) const = 0;
  virtual double max(double v) const = 0;
  virtual uint64_t sum_u64(uint64_t v) const = 0;  // wrapping sum (checksums)
  virtual int64_t sum_i64(int64_t v) const = 0;
  // a[k] = the largest of the ranks' a[k], for k < n: a field that each rank
  // fills where it owns (0 elsewhere, values >= 0; or -HUGE_VAL elsewhere,
  // any values) becomes whole everywhere.
  virtual void max_each(double* a, int64_t n) const = 0;
  // a[k] = the bitwise or of the ranks' a[k], for k < n (0 where a rank
  // does not fill it): bit fields whole everywhere.
  virtual void or_each(uint32_t* a, int64_t n) const = 0;
  // How many ranks hand in partials.
  virtual int ranks() const = 0;
  // out[k] = rank k's n, on every rank.
  virtual void counts(int64_t n, std::vector<int64_t>& out) const = 0;
  // Every rank's bytes[rank] bytes at `mine`, concatenated in rank order
  // into `all` (their sum), on every rank: for what each rank holds a part
  // of and every rank needs whole, in one order (the multigrid's levels).
  virtual void gather_bytes(const void* mine, const std::vector<int64_t>& bytes, void* all) const = 0;
  // This rank's number (0 to ranks() - 1).
  virtual int rank() const = 0;
  // Each rank sends send_bytes[k] bytes to rank k, taken in rank order
  // from `send`, and receives recv_bytes[k] from rank k into `recv`, in
  // rank order: the values of a few rows that other ranks' rows read (the
  // multigrid's finest level divided, DividedLevel). Collective.
  virtual void exchange_bytes(const void* send, const std::vector<int64_t>& send_bytes, void* recv,
                              const std::vector<int64_t>& recv_bytes) const = 0;
};

// gather_bytes for arrays of T: counts[k] values from rank k.
template <class T>
void gather_all(const Reducer& red, const T* mine, const std::vector<int64_t>& counts, T* all,
                std::vector<int64_t>& bytes) {
  bytes.resize(counts.size());
  for (size_t k = 0; k < counts.size(); ++k) bytes[k] = counts[k] * int64_t(sizeof(T));
  red.gather_bytes(mine, bytes, all);
}

// One rank: the owned tiles are all tiles.
class LocalReducer : public Reducer {
 public:
  void sum_tiles(const std::vector<int>& owned, const double* partials, int k,
                 double* out) const override {
    const size_t n = owned.size();
    for (int r = 0; r < k; ++r) {
      double s = 0;
      for (size_t t = 0; t < n; ++t) s += partials[r * n + t];
      out[r] = s;
    }
  }
  double max(double v) const override { return v; }
  uint64_t sum_u64(uint64_t v) const override { return v; }
  int64_t sum_i64(int64_t v) const override { return v; }
  void max_each(double*, int64_t) const override {}
  void or_each(uint32_t*, int64_t) const override {}
  int ranks() const override { return 1; }
  void counts(int64_t n, std::vector<int64_t>& out) const override { out.assign(1, n); }
  void gather_bytes(const void* mine, const std::vector<int64_t>& bytes, void* all) const override {
    if (all != mine && bytes[0] > 0) std::memcpy(all, mine, size_t(bytes[0]));
  }
  int rank() const override { return 0; }
  void exchange_bytes(const void* send, const std::vector<int64_t>& send_bytes, void* recv,
                      const std::vector<int64_t>&) const override {
    if (recv != send && send_bytes[0] > 0) std::memcpy(recv, send, size_t(send_bytes[0]));
  }
};

}  // namespace drape
