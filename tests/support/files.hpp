#pragma once
// Files for the tests that run the program or write outputs: a directory of
// the test program's own and a whole file read back.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace drape::test {

// A directory of this process's own under DRAPE_TEST_TMP (ctest runs test
// cases in parallel processes, so the pid keeps them apart).
inline std::filesystem::path process_tmp_dir(const std::string& program) {
  const std::filesystem::path d = std::filesystem::path(DRAPE_TEST_TMP) / (program + "-" + std::to_string(getpid()));
  std::filesystem::create_directories(d);
  return d;
}

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace drape::test
