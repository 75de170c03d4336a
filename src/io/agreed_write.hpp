#pragma once
// One piece of a collective write (creating a parallel HDF5 file, writing a
// dataset, closing the file) can fail on one rank alone: a full disk, a
// file-size limit or an I/O error strikes the rank whose bytes meet it.
// Every rank runs the piece, then they agree: a failure anywhere is thrown
// on every rank as the same CollectiveError naming the file, so all ranks
// unwind through the same collective closes and none waits for another.
#include <mpi.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

#include "decomp/collective.hpp"
#include "base/error.hpp"

namespace drape {

template <class Piece>
void agreed_write(MPI_Comm comm, const std::string& file, Piece&& piece) {
  std::string error;
  errno = 0;
  try {
    piece();
  } catch (const std::exception& e) {
    error = e.what();
    // HDF5 and MPI-IO lose the system's reason on the way up; errno keeps it.
    if (errno == EFBIG || errno == ENOSPC || errno == EDQUOT || errno == EIO)
      error += std::string(": ") + std::strerror(errno);
  }
  error = first_error(comm, error);
  if (!error.empty()) throw CollectiveError("cannot write " + file + ": " + error);
}

}  // namespace drape
