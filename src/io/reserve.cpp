#include "io/reserve.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cstring>
#include <stdexcept>

namespace drape {

void reserve_file_space(const std::string& path, int64_t bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY);
  if (fd < 0) throw std::runtime_error("cannot open it to claim room: " + std::string(std::strerror(errno)));
  const int rc = ::posix_fallocate(fd, 0, off_t(bytes));  // returns the error, leaves errno alone
  ::close(fd);
  if (rc != 0)
    throw std::runtime_error("no room for " + std::to_string(bytes) + " bytes (" + std::strerror(rc) + ")");
}

int64_t metadata_allowance(int64_t data) { return data / 16 + 4096; }

}  // namespace drape
