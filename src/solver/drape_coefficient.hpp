#pragma once
// The Cusick drape test's figure (BS 5058, ISO 9073-9): the drape
// coefficient DC = (S - D) / (F - D), S the area of the draped specimen's
// shadow on the floor plane (with the support disc's), D the disc's and F
// the flat specimen's. Each area is counted on one raster of square pixels
// over the specimen's reach, a pixel covered where its centre lies in the
// xy projection of a mesh cell (two triangles) or of the disc: the flat
// specimen is the same cells at rest, so a specimen left flat reads 1 and
// the staircase outline of a cut disc costs nothing.
#include <cstdint>
#include <vector>

#include "mesh/cloth.hpp"
#include "mesh/tiles.hpp"
#include "solver/scene.hpp"

namespace drape {

struct DrapeTest {
  double coefficient = 0;  // DC, 0 (hangs straight down) to 1 (flat)
  double shadow = 0;       // m^2: S
  double specimen = 0;     // m^2: F
  double disc = 0;         // m^2: D
  // The folds ("nodes") the shadow's outline makes: the outline's radius
  // about the disc's axis, r(angle) at every degree, rises above and falls
  // back below its mean once per node (by a third of the way to its highest
  // and lowest, so that ripples of the cut's staircase do not count); 0 when the swing is
  // under two spacings (the staircase's own) or 2 % of the specimen's radius.
  int nodes = 0;
};

// Whether the scene is a drape test: a disc cloth on a disc obstacle.
bool is_drape_test(const Scene& s);

// The areas and DC of the cloth's active mesh at positions x (3 per grid
// particle, all of them, e.g. gathered on one rank), rasterised on
// pixels x pixels over a square of side 2.2 x the specimen's radius.
DrapeTest drape_test(const Cloth& c, const double* x, const Scene& s, int pixels = 2048);

// The same over ranks: each covers the cells of its own tiles' particles
// (their corners read from x, its ring's too), the covers are or-ed together
// (every pixel is a cell's or not, whichever rank drew it: the same raster
// and areas on any number of ranks), then the figures come from the
// whole cover (which they take over).
struct DrapeCover {
  std::vector<uint8_t> shadow, specimen;  // pixels x pixels, at x and at rest
};
DrapeCover drape_cover(const Cloth& c, const double* x, const Scene& s, const Tiling& tiling,
                       const std::vector<int>& tiles, int pixels = 2048);
DrapeTest drape_figures(const Cloth& c, const Scene& s, DrapeCover& cover, int pixels = 2048);

}  // namespace drape
