#pragma once
// Run output: DIR/drape.h5 (one file, written collectively by all ranks, in
// global particle order), DIR/drape.xdmf beside it for ParaView, and
// DIR/drape.png. Every file is written under a temporary name and renamed
// once complete, so a failed run never leaves a damaged file behind.
#include <mpi.h>

#include <memory>
#include <string>

#include "io/frame.hpp"
#include "io/picture.hpp"
#include "solver/fabric.hpp"
#include "solver/scene.hpp"

namespace drape {

class Hdf5Output {
 public:
  // Collective over `comm`. Creates DIR/drape.h5.tmp. With resume_step >= 0
  // (a restart) and a DIR/drape.h5 of the same grid, continues a copy of it
  // instead: its frames before resume_step are kept, later ones dropped.
  Hdf5Output(const std::string& dir, MPI_Comm comm, const Scene& scene,
             const std::string& scene_toml, const Fabric& fabric, int ni, int nj,
             int resume_step = -1);
  ~Hdf5Output();  // without finish(): closes and removes the temporary file
  Hdf5Output(const Hdf5Output&) = delete;
  Hdf5Output& operator=(const Hdf5Output&) = delete;

  // Collective: appends one output step (group /frames/NNNNNN).
  void write_frame(const FrameView& f);
  // Collective: closes the file, renames it to drape.h5 and (rank 0) writes
  // drape.xdmf describing every frame as a quadrilateral surface.
  void finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Rank 0 only, full arrays: render_picture (io/picture.hpp) of their samples.
void render_picture(const FrameView& f, const ObstacleSpec& obstacle, const std::string& path,
                    int width = 1024, int height = 768, const std::string& description = "");

}  // namespace drape
