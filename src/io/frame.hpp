#pragma once
// What the writers see of the cloth at one output step: arrays in global
// particle order (p = i*NJ + j) plus the blocks of the grid this rank owns
// (one block, the whole grid, on one rank).
#include <cstdint>
#include <string>
#include <vector>

#include "solver/scene.hpp"

namespace drape {

struct Block {
  int i0, i1, j0, j1;  // half-open particle ranges
};

struct FrameView {
  int ni = 0, nj = 0;
  int step = 0;
  double time = 0;
  const double* x = nullptr;         // 3 per particle
  const double* tension = nullptr;   // 2 per particle: slot [p][d], N/m
  const double* moment = nullptr;    // 2 per particle: slot [p][d], N*m/m
  const double* shear = nullptr;     // 1 per particle, N/m
  // The three force arrays hold particle p at slot[p] (Cloth::slot_of:
  // a rank's own and ghost particles only); null: at p.
  const int32_t* slot = nullptr;
  const uint8_t* flags = nullptr;    // ParticleFlag
  const uint8_t* level = nullptr;    // AMRC level
  std::vector<Block> owned;          // this rank's part; written collectively
};

}  // namespace drape
