#pragma once
// Small HDF5 helpers shared by the run output (drape.h5) and checkpoints:
// RAII handles, attributes, whole-grid datasets written collectively by the
// blocks each rank owns, and checked readers. Failures throw
// std::runtime_error carrying HDF5's innermost error description.
#include <hdf5.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "io/frame.hpp"

namespace drape::h5 {

// The innermost HDF5 error description ("" when none), clearing the stack.
std::string error_text();
[[noreturn]] void fail(const std::string& what);
hid_t check(hid_t id, const std::string& what);
void check_status(herr_t status, const std::string& what);

// Owns one HDF5 identifier; closes it on scope exit, also while unwinding,
// so that a failed write still lets the file be closed.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer close) : id_(id), close_(close) {}
  Handle(Handle&& o) noexcept : id_(std::exchange(o.id_, -1)), close_(o.close_) {}
  Handle& operator=(Handle&& o) noexcept {
    reset();
    id_ = std::exchange(o.id_, -1);
    close_ = o.close_;
    return *this;
  }
  ~Handle() { reset(); }
  hid_t get() const { return id_; }
  void reset() {
    if (id_ >= 0 && close_) close_(id_);
    id_ = -1;
  }
  // Closes now and reports failure (a close can be where data hits the disk).
  void close(const std::string& what) {
    hid_t id = std::exchange(id_, -1);
    if (id >= 0) check_status(close_(id), what);
  }

 private:
  hid_t id_ = -1;
  Closer close_ = nullptr;
};

Handle make_space(const std::vector<hsize_t>& dims);
Handle make_plist(hid_t cls, const std::string& what);
// Groups and datasets without modification times, so identical runs give
// identical files.
Handle untimed_gcpl();
Handle untimed_dcpl();
Handle create_group(hid_t parent, const std::string& name);

// ------------------------------------------------------------ attributes --
void put_string(hid_t obj, const char* name, const std::string& value);
void put_numbers(hid_t obj, const char* name, hid_t file_type, hid_t mem_type, const void* v,
                 size_t n);
void put_double(hid_t obj, const char* name, double v);
void put_pair(hid_t obj, const char* name, double warp, double weft);
void put_int(hid_t obj, const char* name, int64_t v);

bool has_attribute(hid_t obj, const char* name);
std::string get_string(hid_t obj, const char* name);
double get_double(hid_t obj, const char* name);
int64_t get_int(hid_t obj, const char* name);
// An attribute of exactly `count` numbers, read as `mem_type`.
void get_numbers(hid_t obj, const char* name, hid_t mem_type, void* out, size_t count);

// ------------------------------------------------------------- datasets --

// File and memory dataspaces of an (NI x NJ [x C]) array, both selecting the
// union of the owned blocks (or nothing).
struct Selection {
  Handle file, mem;
  hsize_t count = 0;  // elements selected
};
Selection select_blocks(const std::vector<Block>& owned, int ni, int nj, int comps);
// The same file selection for an array of `comps` values a particle held
// at slot[p] (Cloth::slot_of; null: at p, as select_blocks): the owned
// blocks' values packed into `packed` in the file selection's order
// (ascending grid id), the memory side a plain run of them; write from
// `packed` then, or from x where slot is null.
Selection select_held(const std::vector<Block>& owned, int ni, int nj, int comps, const int32_t* slot,
                      const double* x, std::vector<double>& packed);

// Collective: creates `name` under `group` and writes this rank's selection.
void write_dataset(hid_t group, const std::string& name, hid_t file_type, hid_t mem_type,
                   const void* data, const Selection& sel, hid_t dxpl);

// Reads a whole dataset of `count` elements into `out`, after checking that
// it holds exactly that many (a foreign or damaged file fails here).
void read_dataset(hid_t group, const std::string& name, hid_t mem_type, void* out, hsize_t count);
// Reads the `comps` values a particle of an (NI x NJ [x C]) dataset for the
// particles `ids` (ascending grid ids) into `out`, in that order: one
// selection of their runs along rows, so a rank reads only what it holds.
// Null `ids`: the whole dataset. The count is checked as read_dataset's.
void read_particles(hid_t group, const std::string& name, hid_t mem_type, int ni, int nj, int comps,
                    const std::vector<int64_t>* ids, void* out);

}  // namespace drape::h5
