// libFuzzer harness: the checkpoint reader on a damaged file. The input's
// bytes are written to a file (seeds: a real small checkpoint, mutated by
// the fuzzer) and read back as a checkpoint. A damaged file must end in
// InputError; HDF5's own error printing is off (read_checkpoint silences it).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "io/checkpoint.hpp"
#include "base/error.hpp"

namespace {

// One file per process, so parallel fuzzing jobs do not collide; removed at exit.
std::string file_name() {
  return (std::filesystem::temp_directory_path() / ("drape-fuzz-checkpoint-" + std::to_string(::getpid()) + ".h5"))
      .string();
}

const std::string& file_path() {
  static const std::string path = [] {
    std::atexit([] { std::remove(file_name().c_str()); });
    return file_name();
  }();
  return path;
}

// A cloth of the checkpoint's grid holding every particle, as one rank's run would.
drape::Cloth whole_cloth(const drape::Grid& g) {
  drape::Cloth c;
  c.grid = g;
  c.layout.n = c.layout.m = g.n();
  c.z.assign(size_t(c.layout.size()), 0.0);
  c.x1.assign(size_t(3 * g.n()), 0.0);
  c.x2.assign(size_t(3 * g.n()), 0.0);
  c.flags.assign(size_t(g.n()), 0);
  c.level.assign(size_t(g.n()), 0);
  return c;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  {
    std::ofstream out(file_path(), std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  try {
    const drape::CheckpointState ck = drape::read_checkpoint(file_path());
    drape::Cloth c = whole_cloth(ck.grid);
    std::vector<double> eased;
    drape::read_checkpoint_particles(ck, c, eased);
    const drape::Tiling tiling(c.grid.ni, c.grid.nj, 16);
    uint64_t sum = 0;
    for (uint64_t s : drape::checkpoint_tile_sums(c, tiling, eased)) sum += s;
    drape::check_checkpoint_digest(ck, sum);
  } catch (const drape::InputError&) {
  }
  return 0;
}
