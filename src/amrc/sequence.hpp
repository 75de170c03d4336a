#pragma once
// Grid sequencing: the drape found on coarser meshes first. The run starts
// with every quadtree leaf at one coarse level; each time the cloth comes to
// rest, every leaf splits (Amrc::set_uniform_level), and the finer mesh starts
// from the coarser one's rest state, its tensions and moments included. Only
// the finest mesh's rest ends the run. A coarse mesh crosses the long,
// slow part of the drape (the fall, the swing of the sides) at a coarse
// mesh's price; each finer one only has to settle what it resolves anew.
#include "solver/cloth.hpp"

namespace drape {

// The level of the first mesh: the coarsest whose spacing stays within
// `spacing` (m), and coarse enough to keep at least 8 intervals per side;
// 0 (start on the finest mesh) when spacing is 0 or below the grid's.
int sequence_start_level(const Grid& g, double spacing);

}  // namespace drape
