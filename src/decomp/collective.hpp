#pragma once
// The few collective decisions the program's driver and its writers need:
// rank 0 decides (its clock, its file system check, its rename) and every
// rank follows, so all ranks stop, fail or go on together and none waits in
// a collective alone. src/io reaches other ranks only through these (and
// the communicator it hands to parallel HDF5).
#include <mpi.h>

#include <cstdint>
#include <string>

namespace drape {

int rank_of(MPI_Comm comm);
int size_of(MPI_Comm comm);
// How many ranks of comm share this rank's memory (its node), this one included.
int ranks_on_node(MPI_Comm comm);
// Rank 0's value of `decision`, on every rank.
bool root_decides(MPI_Comm comm, bool decision);
// The largest of the ranks' values, on every rank (0 from all: 0).
int max_over_ranks(MPI_Comm comm, int value);
// The bitwise or of the ranks' values, on every rank.
unsigned or_over_ranks(MPI_Comm comm, unsigned value);
// The sum of the ranks' values (mod 2^64), on every rank.
uint64_t sum_over_ranks(MPI_Comm comm, uint64_t value);
// Rank 0's `error` text on every rank (at most 511 bytes; empty: it went well).
std::string root_error(MPI_Comm comm, const std::string& error);
// The lowest failing rank's `error` text on every rank ("" where none failed):
// for a step every rank does, which may fail on any of them (a write).
std::string first_error(MPI_Comm comm, const std::string& error);
// Every rank has arrived.
void wait_for_all(MPI_Comm comm);
// Ends every rank at once, this one naming itself and `what` on stderr: for
// an error that struck this rank alone (a bug, memory), since the others may
// wait for it in a collective, and unwinding would wait in one too (a
// parallel HDF5 file's close).
[[noreturn]] void end_all_ranks(MPI_Comm comm, const std::string& what);

}  // namespace drape
