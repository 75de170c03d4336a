#pragma once
// Bad input (config, fabric data, flags, checkpoints): exit status 2.
// The message names what is wrong and where (file:line, key).
#include <stdexcept>
#include <string>

namespace drape {

struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A failure every rank raises together, agreed through a collective (rank
// 0's verdict on a write, a partition): exit status 1. Every rank can unwind
// from it, closing its files collectively, since none is left waiting.
struct CollectiveError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Numerical failure (NaN, divergence): exit status 3.
struct NumericalError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace drape
