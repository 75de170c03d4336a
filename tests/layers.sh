#!/usr/bin/env bash
# The layers' include rules (docs/development.md): the physics (src/solver,
# src/amrc) never includes mpi.h, a decomp header other than the MPI-free
# tiles.hpp, io beyond its error types, or app; MPI appears only in
# src/decomp, src/app and io's parallel-HDF5 writers. Until each layer is a
# CMake target of its own with PRIVATE dependencies, this check is what
# fails an include that runs back up.
# Usage: layers.sh SRC_DIR
set -euo pipefail
src=$1
fail=0
bad() { echo "layers: $1"; fail=1; }
while IFS= read -r line; do
  bad "physics includes MPI, decomp or app: $line"
done < <(grep -rnE '#include (<mpi\.h>|"decomp/|"app/)' "$src/solver" "$src/amrc" | grep -v '"decomp/tiles.hpp"' || true)
while IFS= read -r line; do
  bad "physics includes io beyond its errors: $line"
done < <(grep -rnE '#include "io/' "$src/solver" "$src/amrc" | grep -v '"io/error.hpp"' || true)
while IFS= read -r line; do
  bad "mpi.h outside decomp, app and io's parallel writers: $line"
done < <(grep -rln '#include <mpi.h>' "$src" | grep -vE "^$src/(decomp|app)/" |
         grep -vE "^$src/io/(output|checkpoint|agreed_write)\.hpp$|^$src/io/(hdf5_output|checkpoint|h5)\.cpp$" || true)
((fail == 0)) && echo "ok: solver and amrc free of MPI, decomp (but tiles), io (but errors) and app; mpi.h only in decomp, app and io's writers"
exit $fail
