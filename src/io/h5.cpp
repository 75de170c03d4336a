// HDF5 helpers shared by the run output and checkpoints (see h5.hpp).
#include "io/h5.hpp"

#include <algorithm>
#include <stdexcept>

namespace drape::h5 {

namespace {

Handle string_type(size_t len) {
  Handle t(check(H5Tcopy(H5T_C_S1), "creating a string type"), H5Tclose);
  check_status(H5Tset_size(t.get(), len + 1), "sizing a string type");  // + terminator
  check_status(H5Tset_strpad(t.get(), H5T_STR_NULLTERM), "string padding");
  check_status(H5Tset_cset(t.get(), H5T_CSET_UTF8), "string character set");
  return t;
}

}  // namespace

// ---------------------------------------------------------------- errors --

// The innermost HDF5 error description, so that messages say what failed.
std::string error_text() {
  std::string text;
  auto walk = [](unsigned n, const H5E_error2_t* e, void* data) -> herr_t {
    auto* out = static_cast<std::string*>(data);
    if (n == 0 && e->desc && *e->desc) *out = e->desc;
    return 0;
  };
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, walk, &text);
  H5Eclear2(H5E_DEFAULT);
  return text;
}

[[noreturn]] void fail(const std::string& what) {
  std::string detail = error_text();
  throw std::runtime_error("HDF5: " + what + (detail.empty() ? "" : " (" + detail + ")"));
}

hid_t check(hid_t id, const std::string& what) {
  if (id < 0) fail(what);
  return id;
}

void check_status(herr_t status, const std::string& what) {
  if (status < 0) fail(what);
}

Handle make_space(const std::vector<hsize_t>& dims) {
  return {check(H5Screate_simple(int(dims.size()), dims.data(), nullptr), "creating a dataspace"),
          H5Sclose};
}

Handle make_plist(hid_t cls, const std::string& what) {
  return {check(H5Pcreate(cls), what), H5Pclose};
}

// ------------------------------------------------------------ attributes --

void put_string(hid_t obj, const char* name, const std::string& value) {
  Handle type = string_type(value.size());
  Handle space(check(H5Screate(H5S_SCALAR), "creating a scalar dataspace"), H5Sclose);
  const std::string what = std::string("attribute '") + name + "'";
  Handle attr(check(H5Acreate2(obj, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
                    "creating " + what),
              H5Aclose);
  check_status(H5Awrite(attr.get(), type.get(), value.c_str()), "writing " + what);
}

void put_numbers(hid_t obj, const char* name, hid_t file_type, hid_t mem_type, const void* v,
                 size_t n) {
  Handle space = n == 1 ? Handle(check(H5Screate(H5S_SCALAR), "creating a scalar dataspace"),
                                 H5Sclose)
                        : make_space({hsize_t(n)});
  const std::string what = std::string("attribute '") + name + "'";
  Handle attr(check(H5Acreate2(obj, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT),
                    "creating " + what),
              H5Aclose);
  check_status(H5Awrite(attr.get(), mem_type, v), "writing " + what);
}

void put_double(hid_t obj, const char* name, double v) {
  put_numbers(obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &v, 1);
}

void put_pair(hid_t obj, const char* name, double warp, double weft) {
  const double v[2] = {warp, weft};
  put_numbers(obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v, 2);
}

void put_int(hid_t obj, const char* name, int64_t v) {
  put_numbers(obj, name, H5T_STD_I64LE, H5T_NATIVE_INT64, &v, 1);
}

// ------------------------------------------------------------- datasets --

Selection select_blocks(const std::vector<Block>& owned, int ni, int nj, int comps) {
  std::vector<hsize_t> dims = {hsize_t(ni), hsize_t(nj)};
  if (comps > 1) dims.push_back(hsize_t(comps));
  Selection s{make_space(dims), make_space(dims), 0};
  H5S_seloper_t op = H5S_SELECT_SET;
  for (const Block& b : owned) {
    if (b.i0 < 0 || b.j0 < 0 || b.i1 > ni || b.j1 > nj)
      throw std::runtime_error("HDF5: an owned block lies outside the grid");
    if (b.i1 <= b.i0 || b.j1 <= b.j0) continue;
    const hsize_t start[3] = {hsize_t(b.i0), hsize_t(b.j0), 0};
    const hsize_t count[3] = {hsize_t(b.i1 - b.i0), hsize_t(b.j1 - b.j0), hsize_t(comps)};
    for (hid_t sp : {s.file.get(), s.mem.get()})
      check_status(H5Sselect_hyperslab(sp, op, start, nullptr, count, nullptr),
                   "selecting an owned block");
    op = H5S_SELECT_OR;
    s.count += count[0] * count[1] * count[2];
  }
  if (op == H5S_SELECT_SET) {  // owns nothing: still joins the collective write
    check_status(H5Sselect_none(s.file.get()), "selecting nothing");
    check_status(H5Sselect_none(s.mem.get()), "selecting nothing");
  }
  return s;
}

Selection select_held(const std::vector<Block>& owned, int ni, int nj, int comps, const int32_t* slot,
                      const double* x, std::vector<double>& packed) {
  Selection s = select_blocks(owned, ni, nj, comps);
  packed.clear();
  if (!slot) return s;
  std::vector<int64_t> ids;
  for (const Block& b : owned)
    for (int i = b.i0; i < b.i1; ++i)
      for (int j = b.j0; j < b.j1; ++j) ids.push_back(int64_t(i) * nj + j);
  std::sort(ids.begin(), ids.end());
  packed.reserve(size_t(comps) * ids.size());
  for (int64_t p : ids) packed.insert(packed.end(), x + comps * int64_t(slot[p]), x + comps * (int64_t(slot[p]) + 1));
  s.mem = make_space({hsize_t(packed.size())});
  if (packed.empty()) check_status(H5Sselect_none(s.mem.get()), "selecting nothing");
  return s;
}

// Dataset creation without modification times, so identical runs give
// identical files.
Handle untimed_dcpl() {
  Handle dcpl = make_plist(H5P_DATASET_CREATE, "creating a dataset property list");
  check_status(H5Pset_obj_track_times(dcpl.get(), false), "switching off time tracking");
  return dcpl;
}

Handle untimed_gcpl() {
  Handle gcpl = make_plist(H5P_GROUP_CREATE, "creating a group property list");
  check_status(H5Pset_obj_track_times(gcpl.get(), false), "switching off time tracking");
  return gcpl;
}

// Collective: creates `name` under `group` and writes this rank's selection.
void write_dataset(hid_t group, const std::string& name, hid_t file_type, hid_t mem_type,
                   const void* data, const Selection& sel, hid_t dxpl) {
  Handle dcpl = untimed_dcpl();
  Handle shape(check(H5Scopy(sel.file.get()), "copying a dataspace"), H5Sclose);
  check_status(H5Sselect_all(shape.get()), "selecting a dataspace");
  Handle ds(check(H5Dcreate2(group, name.c_str(), file_type, shape.get(), H5P_DEFAULT, dcpl.get(),
                             H5P_DEFAULT),
                  "creating dataset '" + name + "'"),
            H5Dclose);
  static const double dummy = 0;  // some buffer, even where nothing is selected
  const void* buf = sel.count > 0 && data ? data : &dummy;
  check_status(H5Dwrite(ds.get(), mem_type, sel.mem.get(), sel.file.get(), dxpl, buf),
               "writing dataset '" + name + "'");
  ds.close("closing dataset '" + name + "'");
}

Handle create_group(hid_t parent, const std::string& name) {
  Handle gcpl = untimed_gcpl();
  return {check(H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT),
                "creating group '" + name + "'"),
          H5Gclose};
}

// ---------------------------------------------------------------- readers --

bool has_attribute(hid_t obj, const char* name) { return H5Aexists(obj, name) > 0; }

namespace {

Handle open_attribute(hid_t obj, const char* name) {
  if (!has_attribute(obj, name)) fail(std::string("attribute '") + name + "' is missing");
  return {check(H5Aopen(obj, name, H5P_DEFAULT), std::string("opening attribute '") + name + "'"),
          H5Aclose};
}

}  // namespace

void get_numbers(hid_t obj, const char* name, hid_t mem_type, void* out, size_t count) {
  Handle attr = open_attribute(obj, name);
  Handle space(check(H5Aget_space(attr.get()), "reading a dataspace"), H5Sclose);
  if (H5Sget_simple_extent_npoints(space.get()) != hssize_t(count))
    fail(std::string("attribute '") + name + "' does not hold " + std::to_string(count) + " value(s)");
  Handle type(check(H5Aget_type(attr.get()), "reading a type"), H5Tclose);
  if (H5Tget_class(type.get()) == H5T_STRING)
    fail(std::string("attribute '") + name + "' is text, not a number");
  check_status(H5Aread(attr.get(), mem_type, out), std::string("reading attribute '") + name + "'");
}

std::string get_string(hid_t obj, const char* name) {
  Handle attr = open_attribute(obj, name);
  Handle type(check(H5Aget_type(attr.get()), "reading a type"), H5Tclose);
  if (H5Tget_class(type.get()) != H5T_STRING || H5Tis_variable_str(type.get()) > 0)
    fail(std::string("attribute '") + name + "' is not fixed-length text");
  const size_t size = H5Tget_size(type.get());
  std::string buf(size, '\0');
  check_status(H5Aread(attr.get(), type.get(), buf.data()),
               std::string("reading attribute '") + name + "'");
  buf.resize(std::min(buf.find('\0'), buf.size()));
  return buf;
}

double get_double(hid_t obj, const char* name) {
  double v = 0;
  get_numbers(obj, name, H5T_NATIVE_DOUBLE, &v, 1);
  return v;
}

int64_t get_int(hid_t obj, const char* name) {
  int64_t v = 0;
  get_numbers(obj, name, H5T_NATIVE_INT64, &v, 1);
  return v;
}

void read_dataset(hid_t group, const std::string& name, hid_t mem_type, void* out, hsize_t count) {
  if (H5Lexists(group, name.c_str(), H5P_DEFAULT) <= 0) fail("dataset '" + name + "' is missing");
  Handle ds(check(H5Dopen2(group, name.c_str(), H5P_DEFAULT), "opening dataset '" + name + "'"),
            H5Dclose);
  Handle space(check(H5Dget_space(ds.get()), "reading a dataspace"), H5Sclose);
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  if (n < 0 || hsize_t(n) != count)
    fail("dataset '" + name + "' holds " + std::to_string(n) + " values, expected " +
         std::to_string(count));
  check_status(H5Dread(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out),
               "reading dataset '" + name + "'");
}

void read_particles(hid_t group, const std::string& name, hid_t mem_type, int ni, int nj, int comps,
                    const std::vector<int64_t>* ids, void* out) {
  const hsize_t all = hsize_t(ni) * hsize_t(nj) * hsize_t(comps);
  if (!ids) return read_dataset(group, name, mem_type, out, all);
  if (H5Lexists(group, name.c_str(), H5P_DEFAULT) <= 0) fail("dataset '" + name + "' is missing");
  Handle ds(check(H5Dopen2(group, name.c_str(), H5P_DEFAULT), "opening dataset '" + name + "'"), H5Dclose);
  Handle file(check(H5Dget_space(ds.get()), "reading a dataspace"), H5Sclose);
  std::vector<hsize_t> dims(3, 1);
  const int rank = H5Sget_simple_extent_ndims(file.get());
  if (rank != (comps > 1 ? 3 : 2) || H5Sget_simple_extent_dims(file.get(), dims.data(), nullptr) != rank ||
      dims[0] != hsize_t(ni) || dims[1] != hsize_t(nj) || (comps > 1 && dims[2] != hsize_t(comps)))
    fail("dataset '" + name + "' is not an " + std::to_string(ni) + " x " + std::to_string(nj) +
         (comps > 1 ? " x " + std::to_string(comps) : std::string()) + " array");
  check_status(H5Sselect_none(file.get()), "selecting nothing");
  for (size_t k = 0; k < ids->size();) {  // one run of consecutive particles of a row
    const int64_t p = (*ids)[k];
    const int i = int(p / nj), j = int(p % nj);
    size_t e = k + 1;
    while (e < ids->size() && (*ids)[e] == (*ids)[e - 1] + 1 && (*ids)[e] % nj != 0) ++e;
    const hsize_t start[3] = {hsize_t(i), hsize_t(j), 0};
    const hsize_t count[3] = {1, hsize_t(e - k), hsize_t(comps)};
    check_status(H5Sselect_hyperslab(file.get(), H5S_SELECT_OR, start, nullptr, count, nullptr),
                 "selecting the held particles of '" + name + "'");
    k = e;
  }
  Handle mem = make_space({std::max<hsize_t>(1, ids->size() * hsize_t(comps))});
  if (ids->empty()) check_status(H5Sselect_none(mem.get()), "selecting nothing");
  check_status(H5Dread(ds.get(), mem_type, mem.get(), file.get(), H5P_DEFAULT, out),
               "reading dataset '" + name + "'");
}

}  // namespace drape::h5
