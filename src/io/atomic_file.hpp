// Writing a whole file so that a reader (or a crash) never sees half of it.
#pragma once

#include <string>

namespace drape {

// Writes `bytes` to path.tmp and renames it to path: the file is either the
// old one or the new one, whole. Throws std::runtime_error naming the file
// on failure (and leaves no path.tmp behind).
void write_file_atomically(const std::string& path, const std::string& bytes);

}  // namespace drape
