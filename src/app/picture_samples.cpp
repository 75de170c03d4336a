#include "app/picture_samples.hpp"

#include <cmath>

#include "decomp/collective.hpp"
#include "decomp/gather.hpp"

namespace drape {

bool picture_samples_on_root(const PicturePlan& plan, const double* x, const Tiling& tiling,
                             const std::vector<int>& owner, MPI_Comm comm, PictureSurface& out,
                             size_t* values_received) {
  const int me = rank_of(comm);
  int broken = 0;
  for (int64_t p : plan.needed)
    if (owner[tiling.tile_of(p)] == me &&
        !(std::isfinite(x[3 * p]) && std::isfinite(x[3 * p + 1]) && std::isfinite(x[3 * p + 2])))
      broken = 1;
  if (max_over_ranks(comm, broken)) return false;
  const std::vector<double> values = gather_listed_on_root(x, 3, plan.needed, tiling, owner, comm);
  if (values_received) *values_received = values.size();
  if (me == 0) out = picture_surface(plan, values.data());
  return true;
}

}  // namespace drape
