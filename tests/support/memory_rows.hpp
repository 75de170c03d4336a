#pragma once
// The solvers' arrays that still follow the grid, by name: what only a
// gradient at z's indices or K's assembly hold. Newton's product vectors (own numbering) and the
// nonlinear CG's (compact) are checked like the rest. Every other array of the evaluator's, Newton's and the
// time loop's tables holds this rank's listed elements, rows or unknowns
// (test_memory, test_mpi_memory_np2 check it).
#include <map>
#include <string>

#include "solver/memory_table.hpp"
#include "solver/time_loop.hpp"

namespace drape::test {

inline bool follows_the_grid(const MemoryTable::Row& r) {
  static const char* const named[] = {
      "Evaluator: residual at z's positions (gradients only)",
      "Evaluator: assembly maps",
      "Evaluator: numeric gradient's copy of z",
  };
  const std::string key = r.owner + ": " + r.array;
  for (const char* n : named)
    if (key == n) return true;
  return false;
}

// The finest level's arrays gathered whole into every rank: allowed only
// with the multigrid on several ranks (0 on one rank and with Jacobi:
// test_memory, test_mpi_memory_np2 check it), K only where its finest
// level is not divided.
inline const char* const kGatheredLevel =
    "NewtonSolver: gathered K (multigrid, several ranks, finest level not divided)";
inline const char* const kGatheredVectors =
    "NewtonSolver: gathered right-hand side and result, the rows' maps (multigrid, several ranks)";

inline const char* const kDividedLevel =
    "NewtonSolver: the finest level divided: ghosts, ring's K rows, K P and level-1 rows, smoother blocks, messages, "
    "vectors (several ranks)";

inline size_t row_bytes(const MemoryTable& t, const std::string& key) {
  size_t bytes = 0;
  for (const MemoryTable::Row& r : t.rows)
    if (r.owner + ": " + r.array == key) bytes += r.bytes;
  return bytes;
}

inline bool listed(const MemoryTable& t, const std::string& key) {
  for (const MemoryTable::Row& r : t.rows)
    if (r.owner + ": " + r.array == key) return true;
  return false;
}

// The time loop's rows (evaluator, solvers, saved unknowns) but those.
inline std::map<std::string, size_t> list_sized_rows(const TimeLoop& loop) {
  MemoryTable t;
  loop.memory(t);
  std::map<std::string, size_t> rows;
  for (const MemoryTable::Row& r : t.rows)
    if (!follows_the_grid(r) && r.owner + ": " + r.array != kGatheredLevel &&
        r.owner + ": " + r.array != kGatheredVectors)
      rows[r.owner + ": " + r.array] += r.bytes;
  return rows;
}

}  // namespace drape::test
