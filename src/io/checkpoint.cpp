// Checkpoint writing (collective, parallel HDF5) and reading (verified).
// Layout and guarantees: see checkpoint.hpp.
#include "io/checkpoint.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <thread>

#include "decomp/collective.hpp"
#include "io/agreed_write.hpp"
#include "base/error.hpp"
#include "io/h5.hpp"
#include "io/reserve.hpp"
#include "io/version.hpp"
#include "solver/checksum.hpp"

namespace drape {

using namespace h5;

namespace {

const char* const kFormat = "drape checkpoint";
const int64_t kFormatVersion = 6;  // 2: counters gained particle_iterations; 3: shear read on crosses; 4: on cells;
                                   // 5: counters gained newton_iterations; 6: eased edges
// Version 5 reads as 6 with no edge easing (its digest is the same then).
const int64_t kOldestReadable = 5;

// ------------------------------------------------------------ the digest --

// A hash of everything particle p carries (its edges' eased rest lengths
// too, when given: 2 a held particle, at pair slots).
uint64_t particle_hash(const Cloth& c, int64_t p, const std::vector<double>& eased) {
  Hasher h(0x452821e638d01377ULL ^ uint64_t(p));
  const double *x1 = c.x1_at(p), *x2 = c.x2_at(p);
  for (int k = 0; k < 3; ++k) {
    h.add(c.z[3 * p + k]);
    h.add(x1[k]);
    h.add(x2[k]);
  }
  for (int k = 0; k < 2; ++k) {
    h.add(c.force(0, 2 * p + k));
    h.add(c.force(1, 2 * p + k));
  }
  h.add(c.force(2, p));
  h.add(uint64_t(c.flags[p]));
  h.add(uint64_t(c.level[p]));
  if (!eased.empty()) {
    h.add(eased[size_t(c.pair_slot(2 * p))]);
    h.add(eased[size_t(c.pair_slot(2 * p + 1))]);
  }
  return h.value();
}

// Sum over the given blocks of their particles' hashes.
uint64_t state_sum(const Cloth& c, const std::vector<Block>& blocks, const std::vector<double>& eased) {
  uint64_t sum = 0;
  for (const Block& b : blocks)
    for (int i = b.i0; i < b.i1; ++i)
      for (int j = b.j0; j < b.j1; ++j) sum += particle_hash(c, c.grid.id(i, j), eased);
  return sum;
}

void add_curve(Hasher& h, const Curve& c) {
  h.add(uint64_t(c.q.size()));
  for (size_t k = 0; k < c.q.size(); ++k) {
    h.add(c.q[k]);
    h.add(c.f[k]);
  }
}

std::vector<double> fabric_numbers(const Fabric& f) {
  std::vector<double> v = {f.density, f.thickness};
  for (const TensileKES& t : f.tensile) v.insert(v.end(), {t.emt, t.lt, t.rt, t.fm});
  for (const BendingKES& b : f.bending) v.insert(v.end(), {b.b, b.hb});
  v.insert(v.end(), {f.shear.g, f.shear.hg});
  return v;
}

// The measured curves by dataset name, in a fixed order.
template <class F>
std::vector<std::pair<std::string, Curve*>> curves_of(F& f) {
  using C = Curve*;
  return {{"tensile_warp_load", C(&f.tensile[0].load)},   {"tensile_warp_unload", C(&f.tensile[0].unload)},
          {"tensile_weft_load", C(&f.tensile[1].load)},   {"tensile_weft_unload", C(&f.tensile[1].unload)},
          {"bending_warp_load", C(&f.bending[0].load)},   {"bending_warp_unload", C(&f.bending[0].unload)},
          {"bending_weft_load", C(&f.bending[1].load)},   {"bending_weft_unload", C(&f.bending[1].unload)},
          {"shear_load", C(&f.shear.load)},               {"shear_unload", C(&f.shear.unload)}};
}

std::vector<double> counter_numbers(const RunCounters& r) {
  return {double(r.iterations), double(r.evaluations), double(r.projections),
          double(r.max_step_iterations), double(r.unconverged), double(r.calm),
          r.dt_min, r.dt_max, r.cg_first_step, double(r.particle_iterations), double(r.newton_iterations)};
}

RunCounters counters_from(const std::vector<double>& v) {
  RunCounters r;
  r.iterations = int64_t(v[0]);
  r.evaluations = int64_t(v[1]);
  r.projections = int64_t(v[2]);
  r.max_step_iterations = int64_t(v[3]);
  r.unconverged = int64_t(v[4]);
  r.calm = int64_t(v[5]);
  r.dt_min = v[6];
  r.dt_max = v[7];
  r.cg_first_step = v[8];
  r.particle_iterations = int64_t(v[9]);
  r.newton_iterations = int64_t(v[10]);
  return r;
}

// Everything that is not per particle.
struct Meta {
  const Grid& grid;
  int step;
  double time, dt, dt_prev;
  const std::string& toml;
  const Fabric& fabric;
  const RunCounters& counters;
  const std::vector<uint8_t>& levels;
  bool eased;
  double ease_until;
};

uint64_t meta_hash(const Meta& m) {
  Hasher h(0xa4093822299f31d0ULL);
  h.add(uint64_t(m.grid.ni));
  h.add(uint64_t(m.grid.nj));
  h.add(uint64_t(m.step));
  for (double v : {m.time, m.dt, m.dt_prev}) h.add(v);
  h.add(m.toml);
  h.add(m.fabric.name);
  h.add(m.fabric.source);
  for (double v : fabric_numbers(m.fabric)) h.add(v);
  Fabric copy = m.fabric;
  for (auto& [name, curve] : curves_of(copy)) add_curve(h, *curve);
  for (double v : counter_numbers(m.counters)) h.add(v);
  h.add(uint64_t(m.levels.size()));
  for (uint8_t l : m.levels) h.add(uint64_t(l));
  if (m.eased) h.add(m.ease_until);
  return h.value();
}

std::string hex(uint64_t v) {
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", (unsigned long long)v);
  return buf;
}

// ------------------------------------------------------------- writing --

// Writes the datasets of one file, each as a piece all ranks agree on
// (agreed_write.hpp): a failed write on any rank fails them all together.
struct Writer {
  MPI_Comm comm;
  std::string file;
  hid_t dxpl;
  void dataset(hid_t group, const std::string& name, hid_t file_type, hid_t mem_type, const void* data,
               const Selection& sel) const {
    agreed_write(comm, file, [&] { write_dataset(group, name, file_type, mem_type, data, sel, dxpl); });
  }
  Handle group(hid_t parent, const std::string& name) const {
    Handle g;
    agreed_write(comm, file, [&] { g = create_group(parent, name); });
    return g;
  }
};

void write_fabric(hid_t root, const Fabric& fabric, int rank, const Writer& w) {
  Handle g = w.group(root, "fabric");
  agreed_write(w.comm, w.file, [&] {
    put_string(g.get(), "name", fabric.name);
    put_string(g.get(), "source", fabric.source);
  });
  auto write_rows = [&](const std::string& name, const std::vector<double>& v, hsize_t cols) {
    const hsize_t rows = v.size() / cols;
    std::vector<hsize_t> dims = {rows};
    if (cols > 1) dims.push_back(cols);
    Selection sel{make_space(dims), make_space(dims), rank == 0 ? hsize_t(v.size()) : 0};
    if (rank != 0) {
      check_status(H5Sselect_none(sel.file.get()), "selecting nothing");
      check_status(H5Sselect_none(sel.mem.get()), "selecting nothing");
    }
    w.dataset(g.get(), name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v.data(), sel);
  };
  write_rows("numbers", fabric_numbers(fabric), 1);
  Fabric copy = fabric;
  for (auto& [name, curve] : curves_of(copy)) {
    if (curve->empty()) continue;
    std::vector<double> rows;
    for (size_t k = 0; k < curve->q.size(); ++k) rows.insert(rows.end(), {curve->q[k], curve->f[k]});
    write_rows(name, rows, 2);
  }
}

// `per` values a particle (x1, x2, a force block) of the owned blocks'
// particles, held in slots on several ranks (select_held).
void write_held(hid_t group, const std::string& name, const Cloth& c, const double* x, int per,
                const std::vector<Block>& owned, const Writer& w) {
  std::vector<double> packed;
  const Selection s = select_held(owned, c.grid.ni, c.grid.nj, per, c.slots(), x, packed);
  w.dataset(group, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, c.slots() ? packed.data() : x, s);
}

void write_state(hid_t root, const Cloth& c, const std::vector<Block>& owned, const std::vector<double>& eased,
                 const Writer& w) {
  Handle g = w.group(root, "state");
  const int ni = c.grid.ni, nj = c.grid.nj;
  const Selection s1 = select_blocks(owned, ni, nj, 1);
  const Selection s3 = select_blocks(owned, ni, nj, 3);
  const hid_t f64 = H5T_IEEE_F64LE, d = H5T_NATIVE_DOUBLE, u8 = H5T_STD_U8LE, c8 = H5T_NATIVE_UINT8;
  w.dataset(g.get(), "positions", f64, d, c.x(), s3);
  write_held(g.get(), "tension", c, c.tension(), 2, owned, w);
  write_held(g.get(), "moment", c, c.moment(), 2, owned, w);
  write_held(g.get(), "shear", c, c.shear(), 1, owned, w);
  write_held(g.get(), "x1", c, c.x1.data(), 3, owned, w);
  write_held(g.get(), "x2", c, c.x2.data(), 3, owned, w);
  w.dataset(g.get(), "flags", u8, c8, c.flags.data(), s1);
  w.dataset(g.get(), "level", u8, c8, c.level.data(), s1);
  if (!eased.empty()) write_held(g.get(), "eased_rest", c, eased.data(), 2, owned, w);
}

// The bytes a checkpoint's datasets and attributes hold, HDF5's metadata aside.
int64_t checkpoint_bytes(const Cloth& c, const std::string& toml, Fabric fabric, size_t levels, bool eased) {
  int64_t bytes = (eased ? 130 : 114) * c.grid.n();  // 14 (16 eased) doubles and 2 bytes per particle
  for (auto& [name, curve] : curves_of(fabric)) bytes += 16 * int64_t(curve->q.size());
  bytes += 8 * int64_t(fabric_numbers(fabric).size() + counter_numbers(RunCounters{}).size());
  return bytes + int64_t(toml.size() + fabric.name.size() + fabric.source.size() + levels);
}

// Test hook: DRAPE_TEST_STALL_CHECKPOINT=POINT:SECONDS pauses each checkpoint
// write at POINT (before-data, mid-data, before-rename, after-rename), rank 0
// saying so on stderr, so that a test can kill the run there and check that
// what is left on disk restarts (tests/kill_checkpoint_np2.sh).
void stall_for_test(const char* point, int rank) {
  const char* spec = std::getenv("DRAPE_TEST_STALL_CHECKPOINT");
  const char* colon = spec ? std::strchr(spec, ':') : nullptr;
  if (!colon || std::string(spec, colon) != point) return;
  if (rank == 0) std::fprintf(stderr, "drape: test: checkpoint write stalled at %s\n", point);
  std::fflush(stderr);
  std::this_thread::sleep_for(std::chrono::duration<double>(std::atof(colon + 1)));
}

// Pushes a file's data to the disk before it is renamed into place.
void sync_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) throw std::runtime_error("cannot open " + path + " to flush it");
  const int rc = ::fsync(fd);
  ::close(fd);
  if (rc != 0) throw std::runtime_error("cannot flush " + path + " to disk");
}

}  // namespace

void write_checkpoint(const std::string& dir, MPI_Comm comm, const Cloth& cloth,
                      const std::vector<Block>& owned, const std::string& scene_toml,
                      const Fabric& fabric, const RunCounters& counters,
                      const std::vector<uint8_t>& amrc_levels, const EasedEdges& eased) {
  const int rank = rank_of(comm);
  const std::string path = dir + "/checkpoint.h5", tmp = path + ".tmp";
  const uint64_t total = sum_over_ranks(comm, state_sum(cloth, owned, eased.rest));
  const Meta meta{cloth.grid, cloth.step,  cloth.time,  cloth.dt,          cloth.dt_prev,    scene_toml,
                  fabric,     counters,    amrc_levels, !eased.rest.empty(), eased.until};
  const uint64_t digest = Hasher::mix(total ^ meta_hash(meta));

  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  try {
    Handle file, dxpl;
    agreed_write(comm, tmp, [&] {
      Handle fapl = make_plist(H5P_FILE_ACCESS, "creating a file access property list");
      check_status(H5Pset_fapl_mpio(fapl.get(), comm, MPI_INFO_NULL), "selecting the MPI-IO driver");
      check_status(H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V18, H5F_LIBVER_V18),
                   "setting the file format version");
      file = Handle(check(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), "cannot create " + tmp),
                    H5Fclose);
      dxpl = make_plist(H5P_DATASET_XFER, "creating a transfer property list");
      check_status(H5Pset_dxpl_mpio(dxpl.get(), H5FD_MPIO_COLLECTIVE), "requesting collective I/O");
    });
    // Room for all of it first: a write HDF5 starts and cannot finish would
    // leave a file that cannot be closed (reserve.hpp).
    agreed_write(comm, tmp, [&] {
      if (rank == 0)
        reserve_file_space(tmp, 0, with_metadata_margin(checkpoint_bytes(cloth, scene_toml, fabric, amrc_levels.size(),
                                                                         !eased.rest.empty())));
    });
    const hid_t root = file.get();
    agreed_write(comm, tmp, [&] {
      put_string(root, "format", kFormat);
      put_int(root, "format_version", kFormatVersion);
      put_string(root, "drape_version", DRAPE_VERSION);
      put_int(root, "ni", cloth.grid.ni);
      put_int(root, "nj", cloth.grid.nj);
      put_int(root, "step", cloth.step);
      put_double(root, "time", cloth.time);
      put_double(root, "dt", cloth.dt);
      put_double(root, "dt_prev", cloth.dt_prev);
      put_string(root, "scene_toml", scene_toml);
      const std::vector<double> cn = counter_numbers(counters);
      put_numbers(root, "counters", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, cn.data(), cn.size());
      if (!eased.rest.empty()) put_double(root, "ease_until", eased.until);
      put_string(root, "digest", hex(digest));
    });
    const Writer w{comm, tmp, dxpl.get()};
    stall_for_test("before-data", rank);
    write_state(root, cloth, owned, eased.rest, w);
    stall_for_test("mid-data", rank);
    write_fabric(root, fabric, rank, w);
    if (!amrc_levels.empty()) {  // rank 0 writes the whole (replicated) tree
      const hsize_t n = amrc_levels.size();
      Selection sel{make_space({n}), make_space({n}), rank == 0 ? n : 0};
      if (rank != 0) {
        check_status(H5Sselect_none(sel.file.get()), "selecting nothing");
        check_status(H5Sselect_none(sel.mem.get()), "selecting nothing");
      }
      w.dataset(root, "amrc_levels", H5T_STD_U8LE, H5T_NATIVE_UINT8, amrc_levels.data(), sel);
    }
    dxpl.reset();
    // Collective: every rank's blocks are in (and the metadata, which may
    // be what meets a full disk).
    agreed_write(comm, tmp, [&] { file.close("closing " + tmp); });
  } catch (const CollectiveError& e) {
    // Every rank is here, its handles closed: the previous checkpoint stays.
    if (rank == 0) std::remove(tmp.c_str());
    throw CollectiveError("checkpoint: " + std::string(e.what()));
  }
  // Rank 0 makes it durable and publishes it; the others learn the outcome.
  std::string error;
  if (rank == 0) {
    try {
      sync_file(tmp);
      stall_for_test("before-rename", rank);
      if (std::rename(tmp.c_str(), path.c_str()) != 0)
        throw std::runtime_error("cannot rename " + tmp + " to " + path);
      stall_for_test("after-rename", rank);
    } catch (const std::exception& e) {
      error = e.what();
      std::remove(tmp.c_str());
    }
  }
  error = root_error(comm, error);
  if (!error.empty()) throw CollectiveError("checkpoint: " + error);
}

// ------------------------------------------------------------- reading --

namespace {

Fabric read_fabric(hid_t root) {
  if (H5Lexists(root, "fabric", H5P_DEFAULT) <= 0) fail("group 'fabric' is missing");
  Handle g(check(H5Gopen2(root, "fabric", H5P_DEFAULT), "opening group 'fabric'"), H5Gclose);
  Fabric f;
  f.name = get_string(g.get(), "name");
  f.source = get_string(g.get(), "source");
  std::vector<double> v(fabric_numbers(f).size());
  read_dataset(g.get(), "numbers", H5T_NATIVE_DOUBLE, v.data(), v.size());
  size_t k = 0;
  f.density = v[k++];
  f.thickness = v[k++];
  for (TensileKES& t : f.tensile) {
    t.emt = v[k++];
    t.lt = v[k++];
    t.rt = v[k++];
    t.fm = v[k++];
  }
  for (BendingKES& b : f.bending) {
    b.b = v[k++];
    b.hb = v[k++];
  }
  f.shear.g = v[k++];
  f.shear.hg = v[k++];
  for (auto& [name, curve] : curves_of(f)) {
    if (H5Lexists(g.get(), name.c_str(), H5P_DEFAULT) <= 0) continue;
    Handle ds(check(H5Dopen2(g.get(), name.c_str(), H5P_DEFAULT), "opening " + name), H5Dclose);
    Handle space(check(H5Dget_space(ds.get()), "reading a dataspace"), H5Sclose);
    const hssize_t n = H5Sget_simple_extent_npoints(space.get());
    if (n <= 0 || n % 2 != 0) fail("curve '" + name + "' is not a list of (q, f) pairs");
    std::vector<double> rows(size_t(n), 0.0);
    read_dataset(g.get(), name, H5T_NATIVE_DOUBLE, rows.data(), hsize_t(n));
    for (size_t r = 0; r < rows.size(); r += 2) {
      curve->q.push_back(rows[r]);
      curve->f.push_back(rows[r + 1]);
    }
  }
  return f;
}

// The per-particle datasets and their values a particle.
const std::pair<const char*, int> kParticleData[] = {{"positions", 3}, {"tension", 2}, {"moment", 2}, {"shear", 1},
                                                     {"x1", 3},        {"x2", 3},      {"flags", 1},  {"level", 1}};

void check_particle_data(hid_t root, bool eased) {
  if (H5Lexists(root, "state", H5P_DEFAULT) <= 0) fail("group 'state' is missing");
  Handle g(check(H5Gopen2(root, "state", H5P_DEFAULT), "opening group 'state'"), H5Gclose);
  for (const auto& [name, per] : kParticleData)
    if (H5Lexists(g.get(), name, H5P_DEFAULT) <= 0) fail("dataset '" + std::string(name) + "' is missing");
  if (eased && H5Lexists(g.get(), "eased_rest", H5P_DEFAULT) <= 0) fail("dataset 'eased_rest' is missing");
}

CheckpointState read_verified(const std::string& path) {
  CheckpointState ck;
  ck.path = path;
  Handle file(check(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT),
                    "cannot be opened as HDF5 (truncated or damaged?)"),
              H5Fclose);
  const hid_t root = file.get();
  if (!has_attribute(root, "format") || get_string(root, "format") != kFormat)
    throw InputError("is an HDF5 file but not a drape checkpoint (no format = \"" +
                     std::string(kFormat) + "\" attribute; drape.h5 outputs cannot be restarted from)");
  const int64_t version = get_int(root, "format_version");
  if (version < kOldestReadable || version > kFormatVersion)
    throw InputError("has checkpoint format version " + std::to_string(version) + "; this drape reads versions " +
                     std::to_string(kOldestReadable) + " to " + std::to_string(kFormatVersion));
  const int64_t ni = get_int(root, "ni"), nj = get_int(root, "nj"), step = get_int(root, "step");
  if (ni < 3 || nj < 3 || ni * nj > INT32_MAX || step < 0)
    throw InputError("holds an impossible grid " + std::to_string(ni) + " x " + std::to_string(nj) +
                     " or step " + std::to_string(step));
  ck.grid.ni = int(ni);
  ck.grid.nj = int(nj);
  ck.step = int(step);
  ck.time = get_double(root, "time");
  ck.dt = get_double(root, "dt");
  ck.dt_prev = get_double(root, "dt_prev");
  if (!(ck.dt > 0) || !(ck.dt_prev > 0) || !std::isfinite(ck.time))
    throw InputError("holds an impossible time " + std::to_string(ck.time) + " or time step");
  ck.scene_toml = get_string(root, "scene_toml");
  std::vector<double> cn(counter_numbers(RunCounters{}).size());
  get_numbers(root, "counters", H5T_NATIVE_DOUBLE, cn.data(), cn.size());
  ck.counters = counters_from(cn);
  ck.eased = has_attribute(root, "ease_until");
  if (ck.eased) ck.ease_until = get_double(root, "ease_until");
  check_particle_data(root, ck.eased);
  ck.fabric = read_fabric(root);
  if (H5Lexists(root, "amrc_levels", H5P_DEFAULT) > 0) {
    ck.amrc_levels.resize(size_t(ni - 1) * (nj - 1));
    read_dataset(root, "amrc_levels", H5T_NATIVE_UINT8, ck.amrc_levels.data(), ck.amrc_levels.size());
  }
  ck.digest = get_string(root, "digest");
  return ck;
}

// Reads `per` values a held particle of dataset `name` (ids: the held
// particles, ascending; null: all) and hands each particle's to `put`.
template <class T, class Put>
void read_held(hid_t g, const char* name, hid_t type, const Grid& grid, int per, const std::vector<int64_t>* ids,
               Put put) {
  const int64_t count = ids ? int64_t(ids->size()) : grid.n();
  std::vector<T> buf(size_t(count * per));
  read_particles(g, name, type, grid.ni, grid.nj, per, ids, buf.data());
  for (int64_t k = 0; k < count; ++k) put(ids ? (*ids)[size_t(k)] : k, &buf[size_t(k * per)]);
}

void read_particles_of(const CheckpointState& ck, Cloth& c, std::vector<double>& eased) {
  Handle file(check(H5Fopen(ck.path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT),
                    "cannot be opened as HDF5 (truncated or damaged?)"),
              H5Fclose);
  Handle g(check(H5Gopen2(file.get(), "state", H5P_DEFAULT), "opening group 'state'"), H5Gclose);
  const std::vector<int64_t> held = c.slots() ? held_particles(c) : std::vector<int64_t>{};
  const std::vector<int64_t>* ids = c.slots() ? &held : nullptr;
  const hid_t d = H5T_NATIVE_DOUBLE, u8 = H5T_NATIVE_UINT8;
  const hid_t gr = g.get();
  read_held<double>(gr, "positions", d, c.grid, 3, ids, [&](int64_t p, const double* v) {
    std::copy(v, v + 3, c.x() + 3 * p);
  });
  for (int b = 0; b < 2; ++b)
    read_held<double>(gr, b == 0 ? "tension" : "moment", d, c.grid, 2, ids, [&](int64_t p, const double* v) {
      c.force(b, 2 * p) = v[0];
      c.force(b, 2 * p + 1) = v[1];
    });
  read_held<double>(gr, "shear", d, c.grid, 1, ids, [&](int64_t p, const double* v) { c.force(2, p) = v[0]; });
  read_held<double>(gr, "x1", d, c.grid, 3, ids, [&](int64_t p, const double* v) { std::copy(v, v + 3, c.x1_at(p)); });
  read_held<double>(gr, "x2", d, c.grid, 3, ids, [&](int64_t p, const double* v) { std::copy(v, v + 3, c.x2_at(p)); });
  read_held<uint8_t>(gr, "flags", u8, c.grid, 1, ids, [&](int64_t p, const uint8_t* v) { c.flags[p] = v[0]; });
  read_held<uint8_t>(gr, "level", u8, c.grid, 1, ids, [&](int64_t p, const uint8_t* v) { c.level[p] = v[0]; });
  eased.clear();
  if (!ck.eased) return;
  eased.assign(size_t(2 * c.layout.m), 0.0);
  read_held<double>(gr, "eased_rest", d, c.grid, 2, ids, [&](int64_t p, const double* v) {
    eased[size_t(c.pair_slot(2 * p))] = v[0];
    eased[size_t(c.pair_slot(2 * p + 1))] = v[1];
  });
}

}  // namespace

CheckpointState read_checkpoint(const std::string& path) {
  const std::string where = "checkpoint " + path + ": ";
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(where + "is a directory; name the file, e.g. " + path + "/checkpoint.h5");
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError(where + "no such file");
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  if (H5Fis_hdf5(path.c_str()) <= 0)
    throw InputError(where + "not an HDF5 file (truncated, damaged or foreign)");
  try {
    return read_verified(path);
  } catch (const InputError& e) {
    throw InputError(where + e.what());
  } catch (const std::exception& e) {
    throw InputError(where + e.what());
  }
}

void read_checkpoint_particles(const CheckpointState& ck, Cloth& cloth, std::vector<double>& eased) {
  if (ck.grid.ni != cloth.grid.ni || ck.grid.nj != cloth.grid.nj)
    throw InputError("checkpoint " + ck.path + ": its grid does not match the scene's");
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  try {
    read_particles_of(ck, cloth, eased);
  } catch (const std::exception& e) {
    throw InputError("checkpoint " + ck.path + ": " + e.what());
  }
  cloth.step = ck.step;
  cloth.time = ck.time;
  cloth.dt = ck.dt;
  cloth.dt_prev = ck.dt_prev;
}

std::vector<uint64_t> checkpoint_tile_sums(const Cloth& cloth, const Tiling& tiling, const std::vector<double>& eased) {
  std::vector<uint64_t> sums(size_t(tiling.count()), 0);
  for (int t = 0; t < tiling.count(); ++t) {
    const TileRange r = tiling.range(t);
    for (int i = r.i0; i < r.i1; ++i)
      for (int j = r.j0; j < r.j1; ++j) {
        const int64_t p = cloth.grid.id(i, j);
        if (cloth.holds(p)) sums[size_t(t)] += particle_hash(cloth, p, eased);
      }
  }
  return sums;
}

void check_checkpoint_digest(const CheckpointState& ck, uint64_t particle_sum) {
  const Meta meta{ck.grid,   ck.step,     ck.time,          ck.dt,   ck.dt_prev, ck.scene_toml,
                  ck.fabric, ck.counters, ck.amrc_levels, ck.eased, ck.ease_until};
  if (hex(Hasher::mix(particle_sum ^ meta_hash(meta))) != ck.digest)
    throw InputError("checkpoint " + ck.path + ": its contents do not match its digest (the file is damaged)");
}

}  // namespace drape
