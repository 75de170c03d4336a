#include "io/atomic_file.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace drape {

void write_file_atomically(const std::string& path, const std::string& bytes) {
  const std::string tmp = path + ".tmp";
  {
    errno = 0;
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    out.close();  // the last bytes reach the file here, and may not fit
    if (!out) {
      // errno names the reason (a full disk, a file-size limit) where the stream does not.
      const std::string why = errno ? std::string(" (") + std::strerror(errno) + ")" : "";
      std::remove(tmp.c_str());
      throw std::runtime_error("cannot write " + path + why);
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error("cannot rename " + tmp + " to " + path);
  }
}

}  // namespace drape
