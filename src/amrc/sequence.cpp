#include "amrc/sequence.hpp"

#include <algorithm>

namespace drape {

int sequence_start_level(const Grid& g, double spacing) {
  const double h = std::max(g.hi, g.hj);
  const int intervals = std::min(g.ni, g.nj) - 1;
  int level = 0;
  while (level < 10 && h * double(2 << level) <= spacing && (intervals >> (level + 1)) >= 8) ++level;
  return level;
}

}  // namespace drape
