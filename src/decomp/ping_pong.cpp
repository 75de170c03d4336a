#include "decomp/ping_pong.hpp"

#include <algorithm>
#include <stdexcept>

namespace drape {

namespace {

// Half the best round trip of a `bytes` message between ranks 0 and 1.
double one_way(MPI_Comm comm, int me, std::vector<char>& buf, int64_t bytes, int repeats) {
  const int tag = 0x7070;
  double best = 1e300;
  for (int k = 0; k <= repeats; ++k) {  // k = 0 warms the path up
    MPI_Barrier(comm);
    const double t0 = MPI_Wtime();
    if (me == 0) {
      MPI_Send(buf.data(), int(bytes), MPI_BYTE, 1, tag, comm);
      MPI_Recv(buf.data(), int(bytes), MPI_BYTE, 1, tag, comm, MPI_STATUS_IGNORE);
    } else if (me == 1) {
      MPI_Recv(buf.data(), int(bytes), MPI_BYTE, 0, tag, comm, MPI_STATUS_IGNORE);
      MPI_Send(buf.data(), int(bytes), MPI_BYTE, 0, tag, comm);
    }
    const double t = 0.5 * (MPI_Wtime() - t0);
    if (k > 0) best = std::min(best, t);
  }
  return best;
}

}  // namespace

void fit_latency_bandwidth(PingPong& p) {
  // Weighted least squares for t = a + b x with weights 1/t^2 (b = 1/beta):
  // a time a rank lost its core in (a shared machine) weighs next to nothing.
  double sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t k = 0; k < p.bytes.size(); ++k) {
    const double x = double(p.bytes[k]), y = p.seconds[k], w = 1.0 / (y * y);
    sw += w;
    sx += w * x;
    sy += w * y;
    sxx += w * x * x;
    sxy += w * x * y;
  }
  const double det = sw * sxx - sx * sx;
  if (p.bytes.size() < 2 || !(det > 0)) throw std::runtime_error("ping_pong: fewer than two distinct sizes");
  const double b = (sw * sxy - sx * sy) / det, a = (sy - b * sx) / sw;
  p.alpha = a;
  p.beta = b > 0 ? 1.0 / b : 0.0;  // 0: no bandwidth term could be measured
}

PingPong ping_pong(MPI_Comm comm, int64_t smallest, int64_t largest, int repeats) {
  int me = 0, ranks = 1;
  MPI_Comm_rank(comm, &me);
  MPI_Comm_size(comm, &ranks);
  if (ranks < 2) throw std::runtime_error("ping_pong: needs at least 2 ranks");
  PingPong p;
  std::vector<char> buf(size_t(largest), 1);
  for (int64_t b = smallest; b <= largest; b *= 2) {
    p.bytes.push_back(b);
    // Small messages are cheap to repeat, and the best of many is what
    // filters a shared machine's scheduling out of a latency.
    p.seconds.push_back(one_way(comm, me, buf, b, b <= (64 << 10) ? 10 * repeats : repeats));
  }
  // Rank 0's clock decides for all.
  MPI_Bcast(p.seconds.data(), int(p.seconds.size()), MPI_DOUBLE, 0, comm);
  fit_latency_bandwidth(p);
  return p;
}

}  // namespace drape
