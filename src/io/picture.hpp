#pragma once
// The cloth as the picture draws it: positions at the grid lines it samples
// (at most about 400 each way), so that the rank drawing it needs no
// whole-cloth array. A sample on an inactive particle (AMRC's coarse cells,
// a disc's cut corners) is filled by linear interpolation along grid lines
// between active particles, rows first, then columns; one no active
// particles bracket is left out.
#include <cstdint>
#include <string>
#include <vector>

#include "io/frame.hpp"

namespace drape {

struct PictureSurface {
  int mi = 0, mj = 0;          // sampled rows, columns
  std::vector<double> x;       // 3 per sample, row by row
  std::vector<uint8_t> ok;     // drawn
};

// How each sample is got from active particles' positions: a row value is
// x(i, jl) alone (jl == jr) or interpolated between x(i, jl) and x(i, jr);
// a sample is row il's value (il == ir) or interpolated between rows il and
// ir's values at its column. il < 0: not drawn.
struct PictureSource {
  int32_t il = -1, ir = -1;
  int32_t jl[2] = {0, 0}, jr[2] = {0, 0};  // for rows il, ir
};

struct PicturePlan {
  int ni = 0, nj = 0;
  std::vector<int> rows, cols;           // the sampled grid lines
  std::vector<PictureSource> source;     // per sample
  std::vector<int64_t> needed;           // particles read, ascending
};

// From the active flags alone (every rank holds them over the whole grid),
// so that every rank finds the same plan.
PicturePlan plan_picture(int ni, int nj, const uint8_t* flags);
// The samples from `values`: 3 per particle of plan.needed, in its order.
PictureSurface picture_surface(const PicturePlan& plan, const double* values);
// The same from whole arrays (flags may be null: all active); non-finite
// positions count as inactive.
PictureSurface picture_surface(const FrameView& f);

// A shaded picture of the cloth (coloured by height) and the obstacle, seen
// from above at an angle. Writes path.tmp, renames. A non-empty
// `description` (printable ASCII) goes into the PNG as a tEXt chunk with the
// keyword "Description": what the picture shows was solved.
void render_picture(const PictureSurface& s, const ObstacleSpec& obstacle, const std::string& path,
                    int width = 1024, int height = 768, const std::string& description = "");

}  // namespace drape
