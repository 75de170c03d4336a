#pragma once
// Loads a fabric from data/kes/<name>.toml (or a path), converting KES units
// to SI and validating every value. Throws InputError naming file, line and key.
#include <string>

#include "solver/fabric.hpp"

namespace drape {

// The directory holding the shipped fabrics: $DRAPE_DATA/kes if set, else an
// installed program's <prefix>/share/drape/data/kes found from its own
// executable, else the source tree's data/kes (compiled in as DRAPE_DATA_DIR).
std::string kes_directory();

// `name_or_path`: a bare name ("denim-A") looks in kes_directory(); anything
// with a '/' or ending in ".toml" is a path.
Fabric load_fabric(const std::string& name_or_path);

// Names of the shipped fabrics, sorted.
std::vector<std::string> list_fabrics();

}  // namespace drape
