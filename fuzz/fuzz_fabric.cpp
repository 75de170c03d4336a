// libFuzzer harness: the fabric loader and the measured-curve reader. The
// input is a fabric TOML, optionally followed by a line "%%" and a curve CSV;
// both are written to a private directory, the CSV as curve.csv, which the
// TOML may name (curve = "curve.csv"). Bad input must end in InputError.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "fuzz/split.hpp"
#include "base/error.hpp"
#include "io/kes.hpp"

namespace {

// One directory per process, so parallel fuzzing jobs do not collide;
// removed at exit.
std::filesystem::path dir_name() {
  return std::filesystem::temp_directory_path() / ("drape-fuzz-fabric-" + std::to_string(::getpid()));
}

const std::filesystem::path& work_dir() {
  static const std::filesystem::path dir = [] {
    std::filesystem::create_directories(dir_name());
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(dir_name(), ec);
    });
    return dir_name();
  }();
  return dir;
}

void write(const std::filesystem::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const drape::fuzz::Parts parts = drape::fuzz::split_at_marker(data, size, "%%");
  const auto fabric = work_dir() / "fabric.toml", curve = work_dir() / "curve.csv";
  write(fabric, parts.head);
  write(curve, parts.tail);
  try {
    (void)drape::load_fabric(fabric.string());
  } catch (const drape::InputError&) {
  }
  return 0;
}
