#include "io/reserve.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cstring>
#include <stdexcept>

namespace drape {

void reserve_file_space(const std::string& path, int64_t from, int64_t end) {
  if (end <= from) return;
  const int fd = ::open(path.c_str(), O_WRONLY);
  if (fd < 0) throw std::runtime_error("cannot open it to claim room: " + std::string(std::strerror(errno)));
  const int rc = ::posix_fallocate(fd, off_t(from), off_t(end - from));  // returns the error, leaves errno alone
  ::close(fd);
  if (rc != 0)
    throw std::runtime_error("no room for " + std::to_string(end) + " bytes (" + std::strerror(rc) + ")");
}

int64_t metadata_allowance(int64_t data) { return data / 16 + 4096; }

}  // namespace drape
