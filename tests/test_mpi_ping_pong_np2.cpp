// Two ranks: the ping-pong behind the scale model's latency and bandwidth.
#include <gtest/gtest.h>
#include <mpi.h>

#include "decomp/ping_pong.hpp"

namespace drape::test {
namespace {

TEST(PingPong, LatencyAndBandwidthArePositive) {
  const PingPong p = ping_pong(MPI_COMM_WORLD, 8, 1 << 20, 5);
  ASSERT_EQ(p.bytes.size(), 18u);  // 8 B .. 1 MiB, doubling
  EXPECT_EQ(p.bytes.front(), 8);
  EXPECT_EQ(p.bytes.back(), 1 << 20);
  EXPECT_GT(p.alpha, 0);
  EXPECT_GT(p.beta, 0);
  // The fitted bandwidth accounts for the megabyte's time within a factor
  // of 10. (Not compared with the small messages' times: on an oversubscribed
  // machine each ping waits for the partner's core, and a small message then
  // took longer than the megabyte.)
  EXPECT_LT(double(1 << 20) / p.beta, 10 * p.seconds.back());
}

TEST(PingPong, FitRecoversAKnownLine) {
  PingPong p;
  for (int64_t b = 8; b <= (1 << 20); b *= 4) {
    p.bytes.push_back(b);
    p.seconds.push_back(2e-6 + double(b) / 5e9);
  }
  fit_latency_bandwidth(p);
  EXPECT_NEAR(p.alpha, 2e-6, 1e-12);
  EXPECT_NEAR(p.beta, 5e9, 1e3);
}

TEST(PingPong, ARankThatLostItsCoreDoesNotSetTheLatency) {
  PingPong p;
  for (int64_t b = 8; b <= (1 << 20); b *= 4) {
    p.bytes.push_back(b);
    p.seconds.push_back(2e-6 + double(b) / 5e9);
  }
  p.seconds[0] = 4e-4;  // 8 bytes took a scheduler's time slice
  p.seconds[2] = 3e-4;
  fit_latency_bandwidth(p);
  EXPECT_LT(p.alpha, 3e-6);
  EXPECT_NEAR(p.beta, 5e9, 5e8);
}

}  // namespace
}  // namespace drape::test
