#pragma once
// Room on disk for a parallel HDF5 file, claimed before HDF5 needs it.
// HDF5 1.10 cannot recover from a write that fails (a full disk, a file-size
// limit): the file then fails to close, and its half-closed handle crashes
// the library's cleanup in MPI_Finalize. So the writers claim the bytes a
// piece will need first, and a refusal ends the run while the file is still
// whole and closes normally.
#include <cstdint>
#include <string>

namespace drape {

// Makes `path` at least `end` bytes long with the blocks from `from` on
// allocated (posix_fallocate; only the new range, which is cheap also where
// the C library has to write it); HDF5 trims the file to its own end when it
// closes it. Throws std::runtime_error with the system's reason when there is
// no room.
void reserve_file_space(const std::string& path, int64_t from, int64_t end);

// What HDF5 allocates for the metadata of `data` bytes of datasets and
// attributes written together (object headers, heaps): generous, so that
// a claim never falls short.
int64_t metadata_allowance(int64_t data);
// Claimed beyond the running total, for HDF5's own bookkeeping blocks.
constexpr int64_t kReserveSlack = int64_t(16) << 10;
// A single piece's claim: its data, the allowance and the slack.
inline int64_t with_metadata_margin(int64_t data) { return data + metadata_allowance(data) + kReserveSlack; }

}  // namespace drape
