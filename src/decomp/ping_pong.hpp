#pragma once
// The network's latency and bandwidth between two ranks, for the scale
// model (docs/performance.md, Scale study): a message of each size goes
// back and forth between ranks 0 and 1; half the best round trip is the
// one-way time, and a line t = alpha + bytes / beta is fitted to those
// times (least squares in relative error, so the small messages weigh as
// much as the large ones, and a time a rank lost its core in hardly at all).
// Other ranks only wait at the barriers.
#include <mpi.h>

#include <cstdint>
#include <vector>

namespace drape {

struct PingPong {
  std::vector<int64_t> bytes;    // message sizes
  std::vector<double> seconds;   // one-way time of each, best of the repeats
  double alpha = 0;              // s, latency
  double beta = 0;               // bytes/s, bandwidth
};

// Collective over `comm` (at least 2 ranks). Sizes from `smallest` to
// `largest` bytes, doubling; each timed `repeats` times after one warm-up
// (10 times as often up to 64 KiB).
// Every rank returns rank 0's figures.
PingPong ping_pong(MPI_Comm comm, int64_t smallest = 8, int64_t largest = 8 << 20, int repeats = 20);

// The fit alone: alpha and beta of t = alpha + bytes / beta, minimising the
// sum of ((alpha + bytes / beta - t) / t)^2.
void fit_latency_bandwidth(PingPong& p);

}  // namespace drape
