// Hdf5Output: one HDF5 file per run, written collectively by all ranks
// (parallel HDF5, MPI-IO driver), plus an XDMF description for ParaView.
//
// Layout of drape.h5
//   /                      attributes: scene, scene_toml, fabric, fabric_source,
//                          fabric_density, fabric_thickness, kes_* (SI), obstacle_*,
//                          ni, nj, drape_version, units
//   /mesh/quads            int32 (NQ x 4), quads (i,j) (i+1,j) (i+1,j+1) (i,j+1)
//   /frames/NNNNNN/        one group per output step (name: the step, 6 digits)
//       positions          float64 (NI x NJ x 3)   m
//       tension            float64 (NI x NJ x 2)   N/m,   [..][0] warp, [..][1] weft
//       moment             float64 (NI x NJ x 2)   N*m/m
//       shear              float64 (NI x NJ)       N/m
//       active             uint8   (NI x NJ)       flags & 1
//       flags              uint8   (NI x NJ)       ParticleFlag bits
//       level              uint8   (NI x NJ)       AMRC level
//     attributes: step (int64), time (float64, s)
//
// Each rank writes exactly the blocks it owns: the frame's arrays span the
// whole grid in global particle order (valid on the owned blocks), and the
// memory and file dataspaces get the same union of hyperslabs, so the file
// does not depend on the number of ranks. The file is DIR/drape.h5.tmp until
// finish() closes it and renames it.
//
// drape.xdmf (XDMF 3) is a temporal collection of uniform grids, one per
// frame: Quadrilateral topology from /mesh/quads, XYZ geometry from the
// frame's positions, node attributes shear, active, level (scalars) and
// tension, moment (two-component arrays: component 0 warp, 1 weft).
// Checked with ParaView 5.11's XDMF Reader and both Xdmf3 readers; ctest
// xdmf_paraview_np2 reads it with pvbatch against drape.h5.
#include <hdf5.h>

#include <charconv>
#include <filesystem>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "decomp/collective.hpp"
#include "io/agreed_write.hpp"
#include "io/atomic_file.hpp"
#include "base/error.hpp"
#include "io/h5.hpp"
#include "io/reserve.hpp"
#include "io/version.hpp"
#include "io/output.hpp"
#include "mesh/cloth.hpp"

namespace drape {

using namespace h5;

namespace {

void put_fabric(hid_t root, const Fabric& fab) {
  put_string(root, "fabric", fab.name);
  put_string(root, "fabric_source", fab.source);
  put_double(root, "fabric_density", fab.density);
  put_double(root, "fabric_thickness", fab.thickness);
  const TensileKES* t = fab.tensile;
  const BendingKES* b = fab.bending;
  put_pair(root, "kes_emt", t[0].emt, t[1].emt);
  put_pair(root, "kes_lt", t[0].lt, t[1].lt);
  put_pair(root, "kes_rt", t[0].rt, t[1].rt);
  put_pair(root, "kes_fm", t[0].fm, t[1].fm);
  put_pair(root, "kes_wt", t[0].wt(), t[1].wt());
  put_pair(root, "kes_b", b[0].b, b[1].b);
  put_pair(root, "kes_hb", b[0].hb, b[1].hb);
  put_double(root, "kes_g", fab.shear.g);
  put_double(root, "kes_hg", fab.shear.hg);
  // Which parts come from measured curves rather than the KES fit.
  const int64_t measured[5] = {!t[0].load.empty(), !t[1].load.empty(), !b[0].load.empty(),
                               !b[1].load.empty(), !fab.shear.load.empty()};
  put_numbers(root, "measured_curves", H5T_STD_I64LE, H5T_NATIVE_INT64, measured, 5);
}

void put_obstacle(hid_t root, const ObstacleSpec& ob) {
  put_string(root, "obstacle_shape", to_string(ob.shape));
  put_numbers(root, "obstacle_center", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, ob.center.data(), 3);
  put_numbers(root, "obstacle_size", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, ob.size.data(), 3);
  put_double(root, "obstacle_radius", ob.radius);
  put_int(root, "obstacle_floor", ob.floor ? 1 : 0);
}

const char* kUnits =
    "SI: positions m; tension, shear N/m; moment N*m/m; time s; fabric_density kg/m^2; "
    "fabric_thickness m; kes_emt, kes_lt, kes_rt fractions; kes_fm N/m; kes_wt J/m^2; "
    "kes_b N*m; kes_hb N; kes_g N/m/rad; kes_hg N/m (hb, hg: half the KES loop widths)";

std::string frame_name(int step) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06d", step);
  return buf;
}

// Shortest text that reads back as the same double.
std::string number_text(double v) {
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

// -------------------------------------------------------------------- XDMF --

struct FrameRecord {
  int step;
  double time;
  bool tension, moment, shear, level;  // which optional datasets exist
};

class XdmfWriter {
 public:
  XdmfWriter(int ni, int nj) : ni_(ni), nj_(nj) {}

  std::string document(const std::vector<FrameRecord>& frames) const {
    std::ostringstream x;
    x << "<?xml version=\"1.0\" ?>\n"
      << "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
      << "<Xdmf Version=\"3.0\">\n"
      << " <Domain>\n"
      << "  <Grid Name=\"drape\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (const FrameRecord& f : frames) grid(x, f);
    x << "  </Grid>\n"
      << " </Domain>\n"
      << "</Xdmf>\n";
    return x.str();
  }

 private:
  int ni_, nj_;

  std::string dims(int comps) const {
    std::string d = std::to_string(ni_) + " " + std::to_string(nj_);
    return comps > 0 ? d + " " + std::to_string(comps) : d;
  }

  static std::string item(const std::string& dims, const char* number, int precision,
                          const std::string& path) {
    return "<DataItem Dimensions=\"" + dims + "\" NumberType=\"" + number + "\" Precision=\"" +
           std::to_string(precision) + "\" Format=\"HDF\">drape.h5:" + path + "</DataItem>";
  }

  void grid(std::ostringstream& x, const FrameRecord& f) const {
    const std::string dir = "/frames/" + frame_name(f.step) + "/";
    const long nq = long(ni_ - 1) * (nj_ - 1);
    x << "   <Grid Name=\"frame_" << frame_name(f.step) << "\" GridType=\"Uniform\">\n"
      << "    <Time Value=\"" << number_text(f.time) << "\"/>\n"
      << "    <Topology TopologyType=\"Quadrilateral\" NumberOfElements=\"" << nq << "\">\n"
      << "     " << item(std::to_string(nq) + " 4", "Int", 4, "/mesh/quads") << "\n"
      << "    </Topology>\n"
      << "    <Geometry GeometryType=\"XYZ\">\n"
      << "     " << item(dims(3), "Float", 8, dir + "positions") << "\n"
      << "    </Geometry>\n";
    if (f.tension) pair(x, "tension", item(dims(2), "Float", 8, dir + "tension"));
    if (f.moment) pair(x, "moment", item(dims(2), "Float", 8, dir + "moment"));
    if (f.shear) scalar(x, "shear", item(dims(0), "Float", 8, dir + "shear"));
    scalar(x, "active", item(dims(0), "UChar", 1, dir + "active"));
    if (f.level) scalar(x, "level", item(dims(0), "UChar", 1, dir + "level"));
    x << "   </Grid>\n";
  }

  static void scalar(std::ostringstream& x, const char* name, const std::string& data) {
    x << "    <Attribute Name=\"" << name << "\" AttributeType=\"Scalar\" Center=\"Node\">\n"
      << "     " << data << "\n"
      << "    </Attribute>\n";
  }

  // A (warp, weft) pair per node: a two-component array in ParaView. Both
  // its XDMF readers (Xdmf2 and Xdmf3) read "Matrix" that way; "Vector"
  // means three components to Xdmf2, and HyperSlab items are skipped by Xdmf3.
  static void pair(std::ostringstream& x, const char* name, const std::string& data) {
    x << "    <Attribute Name=\"" << name << "\" AttributeType=\"Matrix\" Center=\"Node\">\n"
      << "     " << data << "\n"
      << "    </Attribute>\n";
  }
};

}  // namespace

// ---------------------------------------------------------------- Impl --

struct Hdf5Output::Impl {
  std::string dir, tmp_path, final_path;
  MPI_Comm comm = MPI_COMM_NULL;
  int rank = 0;
  int ni = 0, nj = 0;
  Handle file, frames, dxpl;
  std::vector<FrameRecord> records;
  bool finished = false;
  int64_t claimed = 0;  // bytes the file will hold, as far as claimed so far

  void open(const Scene& scene, const std::string& toml, const Fabric& fabric);
  bool reopen(const std::string& toml, int resume_step);
  void rewrite_frames(const std::string& toml, int resume_step);
  void open_file(bool create);
  void write_quads();
  void write(const FrameView& f);
  void close_and_publish();
  void abandon() noexcept;
  // Claims room for `bytes` more of datasets and attributes (and HDF5's
  // metadata for them) before HDF5 allocates them: a write it cannot finish
  // would leave a file that cannot be closed (reserve.hpp). Rank 0 claims.
  void reserve(int64_t bytes) {
    const int64_t before = claimed;
    claimed += bytes + metadata_allowance(bytes);
    agreed([&] {
      if (rank == 0) reserve_file_space(tmp_path, before, claimed + kReserveSlack);
    });
  }
  // Runs one piece of the collective write, agreed on by all ranks (agreed_write.hpp).
  template <class Piece>
  void agreed(Piece&& piece) {
    agreed_write(comm, tmp_path, piece);
  }
};

void Hdf5Output::Impl::open(const Scene& scene, const std::string& toml, const Fabric& fabric) {
  // Errors become exceptions with messages; HDF5's own stack printing would
  // only repeat them, from every rank.
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  agreed([&] { open_file(true); });
  // Room for the header first (see reserve()).
  claimed = 0;
  int64_t fabric_bytes = int64_t(fabric.name.size() + fabric.source.size()) + 256;
  for (const Curve* c : {&fabric.tensile[0].load, &fabric.tensile[0].unload, &fabric.tensile[1].load,
                         &fabric.tensile[1].unload, &fabric.bending[0].load, &fabric.bending[0].unload,
                         &fabric.bending[1].load, &fabric.bending[1].unload, &fabric.shear.load,
                         &fabric.shear.unload})
    fabric_bytes += 16 * int64_t(c->q.size());
  reserve(16 * int64_t(ni - 1) * (nj - 1) + int64_t(toml.size() + scene.name.size()) + fabric_bytes);

  // Attributes are metadata: every rank writes the same values.
  hid_t root = file.get();
  agreed([&] {
    put_string(root, "scene", scene.name);
    put_string(root, "scene_toml", toml);
    put_fabric(root, fabric);
    put_obstacle(root, scene.obstacle);
    put_int(root, "ni", ni);
    put_int(root, "nj", nj);
    put_string(root, "drape_version", DRAPE_VERSION);
    put_string(root, "units", kUnits);
    frames = create_group(root, "frames");
  });
  write_quads();
}

void Hdf5Output::Impl::open_file(bool create) {
  Handle fapl = make_plist(H5P_FILE_ACCESS, "creating a file access property list");
  check_status(H5Pset_fapl_mpio(fapl.get(), comm, MPI_INFO_NULL), "selecting the MPI-IO driver");
  // 1.8 object headers: large attributes (a long scene_toml) go to dense
  // storage, and HDF5 1.8 and later can still read the file.
  check_status(H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V18, H5F_LIBVER_V18),
               "setting the file format version");
  const hid_t id = create ? H5Fcreate(tmp_path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get())
                          : H5Fopen(tmp_path.c_str(), H5F_ACC_RDWR, fapl.get());
  file = Handle(check(id, (create ? "cannot create " : "cannot open ") + tmp_path), H5Fclose);
  dxpl = make_plist(H5P_DATASET_XFER, "creating a transfer property list");
  check_status(H5Pset_dxpl_mpio(dxpl.get(), H5FD_MPIO_COLLECTIVE), "requesting collective I/O");
}

// A restart continues the run's drape.h5 (a copy, published on finish like
// a new file) so the animation has no gap; false when there is none to
// continue, or it is of another grid.
bool Hdf5Output::Impl::reopen(const std::string& toml, int resume_step) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  // A copy that fails (a full disk) is an error: starting a new file would
  // publish it over the run's frames.
  int ok = 0;
  std::string error;
  if (rank == 0) {
    std::error_code ec;
    ok = std::filesystem::is_regular_file(final_path, ec);
    if (ok && !std::filesystem::copy_file(final_path, tmp_path, std::filesystem::copy_options::overwrite_existing,
                                          ec))
      error = "cannot copy " + final_path + " to " + tmp_path + ": " + ec.message();
  }
  error = root_error(comm, error);
  if (!error.empty()) throw CollectiveError("HDF5 output: " + error);
  if (!root_decides(comm, ok)) return false;
  if (rank == 0) claimed = int64_t(std::filesystem::file_size(tmp_path));
  bool same_grid = false;
  agreed([&] {
    open_file(false);
    const hid_t root = file.get();
    same_grid = get_int(root, "ni") == ni && get_int(root, "nj") == nj && H5Lexists(root, "frames", H5P_DEFAULT) > 0;
  });
  if (!same_grid) {
    file.reset();
    return false;
  }
  reserve(int64_t(toml.size()));  // the new scene_toml
  agreed([&] { rewrite_frames(toml, resume_step); });
  return true;
}

// The continued copy: this run's scene, the frames before resume_step.
void Hdf5Output::Impl::rewrite_frames(const std::string& toml, int resume_step) {
  const hid_t root = file.get();
  check_status(H5Adelete(root, "scene_toml"), "replacing attribute 'scene_toml'");
  put_string(root, "scene_toml", toml);
  frames = Handle(check(H5Gopen2(root, "frames", H5P_DEFAULT), "opening group /frames"), H5Gclose);
  std::vector<std::string> names;
  auto collect = [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
    static_cast<std::vector<std::string>*>(data)->push_back(name);
    return 0;
  };
  check_status(H5Literate(frames.get(), H5_INDEX_NAME, H5_ITER_INC, nullptr, collect, &names),
               "listing /frames");
  for (const std::string& name : names) {
    Handle g(check(H5Gopen2(frames.get(), name.c_str(), H5P_DEFAULT), "opening frame " + name), H5Gclose);
    const int step = int(get_int(g.get(), "step"));
    const double time = get_double(g.get(), "time");
    auto has = [&](const char* ds) { return H5Lexists(g.get(), ds, H5P_DEFAULT) > 0; };
    const FrameRecord r{step, time, has("tension"), has("moment"), has("shear"), has("level")};
    g.reset();
    if (step >= resume_step)
      check_status(H5Ldelete(frames.get(), name.c_str(), H5P_DEFAULT), "dropping frame " + name);
    else
      records.push_back(r);
  }
}

// Quad q = i*(NJ-1) + j: (i,j) (i+1,j) (i+1,j+1) (i,j+1), counter-clockwise
// seen from +z when i runs along x and j along y. Rank 0 writes it all.
void Hdf5Output::Impl::write_quads() {
  Handle mesh;
  agreed([&] { mesh = create_group(file.get(), "mesh"); });
  const hsize_t nq = hsize_t(ni - 1) * hsize_t(nj - 1);
  std::vector<int32_t> quads;
  if (rank == 0) {
    quads.reserve(nq * 4);
    for (int i = 0; i + 1 < ni; ++i)
      for (int j = 0; j + 1 < nj; ++j) {
        const int32_t p = int32_t(i) * nj + j;
        quads.insert(quads.end(), {p, p + nj, p + nj + 1, p + 1});
      }
  }
  Selection sel{make_space({nq, 4}), make_space({nq, 4}), rank == 0 ? nq * 4 : 0};
  if (rank != 0) {
    check_status(H5Sselect_none(sel.file.get()), "selecting nothing");
    check_status(H5Sselect_none(sel.mem.get()), "selecting nothing");
  }
  agreed([&] {
    write_dataset(mesh.get(), "quads", H5T_STD_I32LE, H5T_NATIVE_INT32, quads.data(), sel, dxpl.get());
  });
}

namespace {

// What is wrong with this rank's frame, or "".
std::string frame_problem(const FrameView& f, int ni, int nj) {
  if (f.ni != ni || f.nj != nj)
    return "frame is " + std::to_string(f.ni) + "x" + std::to_string(f.nj) + ", file is " +
           std::to_string(ni) + "x" + std::to_string(nj);
  if (!f.x || !f.flags) return "frame without positions or flags";
  for (const Block& b : f.owned)
    if (b.i0 < 0 || b.j0 < 0 || b.i1 > ni || b.j1 > nj) return "an owned block lies outside the grid";
  return "";
}

}  // namespace

void Hdf5Output::Impl::write(const FrameView& f) {
  // Ranks agree on the frame before any collective HDF5 call, so that a bad
  // frame on one rank cannot leave the others waiting. Optional arrays must
  // be given on all ranks or on none (dataset creation is collective).
  const std::string problem = frame_problem(f, ni, nj);
  // One or over ranks: bits 0-3 the arrays some rank has, 4-7 those some
  // rank lacks, 8 a rank's problem.
  const unsigned has = (f.tension ? 1u : 0u) | (f.moment ? 2u : 0u) | (f.shear ? 4u : 0u) | (f.level ? 8u : 0u);
  const unsigned all = or_over_ranks(comm, has | (~has & 15u) << 4 | (problem.empty() ? 0u : 256u));
  if (all & 256u)
    throw CollectiveError("HDF5 output: " +
                          (problem.empty() ? std::string("another rank's frame is invalid") : problem));
  if (all & (all >> 4) & 15u) throw CollectiveError("HDF5 output: ranks disagree on the arrays of a frame");

  const std::string name = frame_name(f.step);
  const int64_t n = int64_t(ni) * nj;
  reserve(n * (24 + (f.tension ? 16 : 0) + (f.moment ? 16 : 0) + (f.shear ? 8 : 0) + 3));
  Handle group;
  agreed([&] {
    group = create_group(frames.get(), name);
    put_int(group.get(), "step", f.step);
    put_double(group.get(), "time", f.time);
  });

  // active and flags as whole-grid arrays, filled where this rank owns.
  std::vector<uint8_t> active(size_t(ni) * nj, 0);
  for (const Block& b : f.owned)
    for (int i = b.i0; i < b.i1; ++i)
      for (int j = b.j0; j < b.j1; ++j) {
        const size_t p = size_t(i) * nj + j;
        active[p] = f.flags[p] & kActive;
      }

  const Selection s1 = select_blocks(f.owned, ni, nj, 1);
  const Selection s2 = select_blocks(f.owned, ni, nj, 2);
  const Selection s3 = select_blocks(f.owned, ni, nj, 3);
  const hid_t g = group.get(), x = dxpl.get();
  const hid_t f64 = H5T_IEEE_F64LE, d = H5T_NATIVE_DOUBLE, u8 = H5T_STD_U8LE, c = H5T_NATIVE_UINT8;
  auto put = [&](const char* ds, hid_t file_type, hid_t mem_type, const void* v, const Selection& s) {
    agreed([&] { write_dataset(g, ds, file_type, mem_type, v, s, x); });
  };
  put("positions", f64, d, f.x, s3);
  // The forces, held in slots on several ranks.
  auto put_held = [&](const char* ds, const double* v, int comps, const Selection& s) {
    if (!f.slot) return put(ds, f64, d, v, s);
    std::vector<double> packed;
    const Selection held = select_held(f.owned, ni, nj, comps, f.slot, v, packed);
    put(ds, f64, d, packed.data(), held);
  };
  if (f.tension) put_held("tension", f.tension, 2, s2);
  if (f.moment) put_held("moment", f.moment, 2, s2);
  if (f.shear) put_held("shear", f.shear, 1, s1);
  put("active", u8, c, active.data(), s1);
  put("flags", u8, c, f.flags, s1);
  if (f.level) put("level", u8, c, f.level, s1);
  agreed([&] {
    group.close("closing group /frames/" + name);
    check_status(H5Fflush(file.get(), H5F_SCOPE_LOCAL), "flushing " + tmp_path);
  });
  records.push_back({f.step, f.time, bool(f.tension), bool(f.moment), bool(f.shear),
                     bool(f.level)});
}

void Hdf5Output::Impl::close_and_publish() {
  agreed([&] {
    frames.close("closing group /frames");
    dxpl.reset();
    file.close("closing " + tmp_path);  // collective: every rank's data is in
  });
  wait_for_all(comm);
  // Rank 0 publishes both files; the others learn whether that worked.
  std::string error;
  if (rank == 0) {
    try {
      if (std::rename(tmp_path.c_str(), final_path.c_str()) != 0)
        throw std::runtime_error("cannot rename " + tmp_path + " to " + final_path);
      write_file_atomically(dir + "/drape.xdmf", XdmfWriter(ni, nj).document(records));
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
  error = root_error(comm, error);
  finished = true;
  if (!error.empty()) throw CollectiveError("HDF5 output: " + error);
}

// Collective, like the close it makes; removes the incomplete file.
void Hdf5Output::Impl::abandon() noexcept {
  frames.reset();
  dxpl.reset();
  file.reset();
  if (rank == 0) std::remove(tmp_path.c_str());
}

// ------------------------------------------------------------ interface --

Hdf5Output::Hdf5Output(const std::string& dir, MPI_Comm comm, const Scene& scene,
                       const std::string& scene_toml, const Fabric& fabric, int ni, int nj,
                       int resume_step)
    : impl_(std::make_unique<Impl>()) {
  if (ni < 2 || nj < 2) throw std::runtime_error("HDF5 output: the grid needs 2x2 particles at least");
  Impl& m = *impl_;
  m.dir = dir.empty() ? "." : dir;
  m.tmp_path = m.dir + "/drape.h5.tmp";
  m.final_path = m.dir + "/drape.h5";
  m.comm = comm;
  m.ni = ni;
  m.nj = nj;
  m.rank = rank_of(comm);
  try {
    if (resume_step < 0 || !m.reopen(scene_toml, resume_step)) m.open(scene, scene_toml, fabric);
  } catch (...) {
    m.abandon();
    throw;
  }
}

Hdf5Output::~Hdf5Output() {
  if (impl_ && !impl_->finished) impl_->abandon();
}

void Hdf5Output::write_frame(const FrameView& f) {
  if (impl_->finished) throw std::runtime_error("HDF5 output: write_frame after finish");
  impl_->write(f);
}

void Hdf5Output::finish() {
  if (impl_->finished) return;
  impl_->close_and_publish();
}

}  // namespace drape
