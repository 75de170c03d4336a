// drape.h5 written by two ranks, each its own blocks, must hold exactly what
// one rank writes alone (MPI_COMM_SELF): every dataset and attribute, byte
// for byte, and the same XDMF text. Runs under mpiexec -n 2.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "io/output.hpp"
#include "mesh/cloth.hpp"
#include "support/files.hpp"

namespace fs = std::filesystem;
using namespace drape;

namespace {

int rank_of(MPI_Comm c) {
  int r = 0;
  MPI_Comm_rank(c, &r);
  return r;
}

// Rank 0 empties the directory; everyone waits for it.
std::string shared_dir(const std::string& name) {
  const fs::path d = fs::path(DRAPE_TEST_TMP) / ("np2_" + name);
  if (rank_of(MPI_COMM_WORLD) == 0) {
    fs::remove_all(d);
    fs::create_directories(d);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  return d.string();
}

using test::slurp;

const int NI = 9, NJ = 7;

// Whole-grid arrays in global order. True values on the owned blocks only;
// elsewhere poison, so a write outside a rank's blocks would show.
struct Frame {
  int step;
  std::vector<double> x, tension, moment, shear;
  std::vector<uint8_t> flags, level;
  std::vector<Block> owned;

  Frame(int step_, const std::vector<Block>& blocks) : step(step_), owned(blocks) {
    const size_t n = size_t(NI) * NJ;
    x.assign(3 * n, NAN), tension.assign(2 * n, -1e300), moment.assign(2 * n, 1e300);
    shear.assign(n, NAN), flags.assign(n, 0xEE), level.assign(n, 0xDD);
    for (const Block& b : blocks)
      for (int i = b.i0; i < b.i1; ++i)
        for (int j = b.j0; j < b.j1; ++j) {
          const size_t p = size_t(i) * NJ + j;
          for (int c = 0; c < 3; ++c) x[3 * p + c] = step * 1e3 + i + 0.01 * j + 1e-4 * c;
          for (int c = 0; c < 2; ++c) tension[2 * p + c] = std::sin(double(p + c + step));
          for (int c = 0; c < 2; ++c) moment[2 * p + c] = std::cos(double(p * 3 + c - step));
          shear[p] = 0.5 * p - step;
          flags[p] = (i + j) % 3 == 0 ? 0 : (i == 0 ? kActive | kFixed : kActive);
          level[p] = uint8_t((i / 2 + j / 2 + step) % 3);
        }
  }
  FrameView view() const {
    FrameView f;
    f.ni = NI, f.nj = NJ, f.step = step, f.time = step * 2.5e-4;
    f.x = x.data(), f.tension = tension.data(), f.moment = moment.data();
    f.shear = shear.data(), f.flags = flags.data(), f.level = level.data();
    f.owned = owned;
    return f;
  }
};

void write_run(const std::string& dir, MPI_Comm comm, const std::vector<Block>& mine) {
  Scene scene;
  scene.name = "np2";
  Fabric fabric;
  fabric.name = "denim-P";
  fabric.source = "test";
  Hdf5Output out(dir, comm, scene, "name = \"np2\"\n", fabric, NI, NJ);
  for (int step : {5, 10}) out.write_frame(Frame(step, mine).view());
  out.finish();
}

// --------------------------------------------------- generic comparison --

struct Id {
  hid_t id;
  herr_t (*close)(hid_t);
  ~Id() {
    if (id >= 0) close(id);
  }
};

// Every object's path and kind.
std::map<std::string, H5O_type_t> objects(hid_t file) {
  std::map<std::string, H5O_type_t> all;
  H5Ovisit(
      file, H5_INDEX_NAME, H5_ITER_INC,
      [](hid_t, const char* name, const H5O_info_t* info, void* data) -> herr_t {
        (*static_cast<std::map<std::string, H5O_type_t>*>(data))[name] = info->type;
        return 0;
      },
      &all);
  return all;
}

// A dataset's shape, type and raw bytes (read in its own file type).
std::vector<char> dataset_bytes(hid_t file, const std::string& path, std::vector<hsize_t>& dims,
                                size_t& type_size, H5T_class_t& cls) {
  Id ds{H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose};
  Id sp{H5Dget_space(ds.id), H5Sclose};
  Id ty{H5Dget_type(ds.id), H5Tclose};
  dims.assign(H5Sget_simple_extent_ndims(sp.id), 0);
  H5Sget_simple_extent_dims(sp.id, dims.data(), nullptr);
  type_size = H5Tget_size(ty.id);
  cls = H5Tget_class(ty.id);
  std::vector<char> b(size_t(H5Sget_simple_extent_npoints(sp.id)) * type_size);
  H5Dread(ds.id, ty.id, H5S_ALL, H5S_ALL, H5P_DEFAULT, b.data());
  return b;
}

std::map<std::string, std::vector<char>> attributes(hid_t file, const std::string& path) {
  Id obj{H5Oopen(file, path.c_str(), H5P_DEFAULT), H5Oclose};
  std::map<std::string, std::vector<char>> all;
  struct Ctx {
    std::map<std::string, std::vector<char>>* out;
  } ctx{&all};
  H5Aiterate2(
      obj.id, H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t loc, const char* name, const H5A_info_t*, void* data) -> herr_t {
        Id a{H5Aopen(loc, name, H5P_DEFAULT), H5Aclose};
        Id ty{H5Aget_type(a.id), H5Tclose};
        Id sp{H5Aget_space(a.id), H5Sclose};
        std::vector<char> b(size_t(H5Sget_simple_extent_npoints(sp.id)) * H5Tget_size(ty.id));
        H5Aread(a.id, ty.id, b.data());
        // Tag the bytes with the type class so a changed type shows too.
        b.push_back(char(H5Tget_class(ty.id)));
        (*static_cast<Ctx*>(data)->out)[name] = b;
        return 0;
      },
      &ctx);
  return all;
}

// ASSERTs here return from this function only: the caller still reaches
// its barriers.
void expect_same_files(const std::string& a_path, const std::string& b_path) {
  Id a{H5Fopen(a_path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  Id b{H5Fopen(b_path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  ASSERT_GE(a.id, 0) << a_path;
  ASSERT_GE(b.id, 0) << b_path;
  const auto objs = objects(a.id);
  ASSERT_EQ(objs, objects(b.id));
  int datasets = 0;
  for (const auto& [name, type] : objs) {
    EXPECT_EQ(attributes(a.id, name), attributes(b.id, name)) << "attributes of " << name;
    if (type != H5O_TYPE_DATASET) continue;
    ++datasets;
    std::vector<hsize_t> da, db;
    size_t sa = 0, sb = 0;
    H5T_class_t ca, cb;
    const auto ba = dataset_bytes(a.id, name, da, sa, ca);
    const auto bb = dataset_bytes(b.id, name, db, sb, cb);
    EXPECT_EQ(da, db) << name;
    EXPECT_EQ(sa, sb) << name;
    EXPECT_EQ(ca, cb) << name;
    EXPECT_TRUE(ba == bb) << "contents of " << name << " differ";
  }
  EXPECT_EQ(datasets, 1 + 2 * 7);  // quads + 7 arrays per frame
}

// Writes the reference with rank 0 alone, then the same run with both
// ranks owning `blocks[rank]`, and compares.
void check_matches_one_rank(const std::string& name, const std::vector<Block> blocks[2]) {
  const std::string ref = shared_dir(name + "_ref"), par = shared_dir(name + "_par");
  const int rank = rank_of(MPI_COMM_WORLD);
  if (rank == 0) write_run(ref, MPI_COMM_SELF, {{0, NI, 0, NJ}});
  MPI_Barrier(MPI_COMM_WORLD);
  write_run(par, MPI_COMM_WORLD, blocks[rank]);
  if (rank == 0) {
    EXPECT_FALSE(fs::exists(par + "/drape.h5.tmp"));
    expect_same_files(ref + "/drape.h5", par + "/drape.h5");
    EXPECT_EQ(slurp(ref + "/drape.xdmf"), slurp(par + "/drape.xdmf"));
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

}  // namespace

TEST(ParallelOutput, RanksSplitByRows) {
  ASSERT_EQ([] { int n = 0; MPI_Comm_size(MPI_COMM_WORLD, &n); return n; }(), 2);
  const std::vector<Block> blocks[2] = {{{0, 4, 0, 3}, {0, 4, 3, NJ}}, {{4, NI, 0, NJ}}};
  check_matches_one_rank("rows", blocks);
}

TEST(ParallelOutput, OneRankOwnsNothing) {
  const std::vector<Block> blocks[2] = {{{0, 3, 0, NJ}, {3, 6, 0, NJ}, {6, NI, 0, NJ}}, {}};
  check_matches_one_rank("nothing", blocks);
}

TEST(ParallelOutput, ScatteredTilesClippedAtTheBorder) {
  // 4x4 tiles, the last ones clipped, dealt out like a chequerboard.
  std::vector<Block> blocks[2];
  for (int i0 = 0, ti = 0; i0 < NI; i0 += 4, ++ti)
    for (int j0 = 0, tj = 0; j0 < NJ; j0 += 4, ++tj)
      blocks[(ti + tj) % 2].push_back({i0, std::min(i0 + 4, NI), j0, std::min(j0 + 4, NJ)});
  check_matches_one_rank("tiles", blocks);
}

namespace {

// Each rank writes its half of a frame, changed by `edit(rank, view)`: both
// ranks must throw, each with `want[rank]` in its message, rather than one
// waiting in a collective call, and the run must leave nothing behind.
template <class Edit>
void expect_refused_on_both(const std::string& name, Edit&& edit, const char* const want[2]) {
  const std::string dir = shared_dir(name);
  {
    Scene scene;
    Fabric fabric;
    Hdf5Output out(dir, MPI_COMM_WORLD, scene, "", fabric, NI, NJ);
    const int rank = rank_of(MPI_COMM_WORLD);
    Frame frame(1, {{rank * 5, rank ? NI : 5, 0, NJ}});
    FrameView view = frame.view();
    edit(rank, view);
    try {
      out.write_frame(view);
      ADD_FAILURE() << "rank " << rank << " wrote the frame";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(want[rank]), std::string::npos) << e.what();
    }
  }
  MPI_Barrier(MPI_COMM_WORLD);
  if (rank_of(MPI_COMM_WORLD) == 0) {
    EXPECT_TRUE(fs::is_empty(dir));
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

}  // namespace

TEST(ParallelOutput, BadFrameOnOneRankFailsOnBoth) {
  // Rank 1 names a block outside the grid; each rank says whose frame it was.
  const char* const want[2] = {"another rank's frame", "outside the grid"};
  expect_refused_on_both("bad_block", [](int rank, FrameView& v) {
    if (rank == 1) v.owned = {{5, NI + 1, 0, NJ}};
  }, want);
}

TEST(ParallelOutput, RanksDisagreeingOnTheArraysFailOnBoth) {
  // Dataset creation is collective: shear on one rank only is refused on both.
  const char* const want[2] = {"ranks disagree", "ranks disagree"};
  expect_refused_on_both("disagree", [](int rank, FrameView& v) {
    if (rank == 1) v.shear = nullptr;
  }, want);
}

TEST(ParallelOutput, AbandonedRunLeavesNothing) {
  const std::string dir = shared_dir("abandon");
  {
    Scene scene;
    Fabric fabric;
    Hdf5Output out(dir, MPI_COMM_WORLD, scene, "", fabric, NI, NJ);
    const int rank = rank_of(MPI_COMM_WORLD);
    out.write_frame(Frame(1, {{rank * 5, rank ? NI : 5, 0, NJ}}).view());
  }
  MPI_Barrier(MPI_COMM_WORLD);
  if (rank_of(MPI_COMM_WORLD) == 0) {
    EXPECT_TRUE(fs::is_empty(dir));
  }
  MPI_Barrier(MPI_COMM_WORLD);
}
