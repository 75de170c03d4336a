#!/usr/bin/env bash
# The layers' include rules (docs/development.md): each folder of src/ may
# include its own headers and those of the layers below it, never one above:
#   base -> mesh -> solver -> amrc -> decomp -> io -> app
# and mpi.h appears only in decomp, app and io's parallel-HDF5 writers. Each
# layer is a library linking only the ones below and compiling against an
# include root that holds only those layers' folders (src/CMakeLists.txt), so
# the build fails such an include too; this check reads the sources alone.
# Usage: layers.sh SRC_DIR
set -euo pipefail
src=$1
order=(base mesh solver amrc decomp io app)
fail=0
bad() { echo "layers: $1"; fail=1; }
for ((k = 0; k < ${#order[@]}; ++k)); do
  layer=${order[k]}
  [[ -d $src/$layer ]] || { bad "no folder $src/$layer"; continue; }
  above=("${order[@]:k+1}")
  ((${#above[@]})) || continue
  pattern="#include \"($(IFS='|'; echo "${above[*]}"))/"
  while IFS= read -r line; do
    bad "$layer includes a layer above it: $line"
  done < <(grep -rnE "$pattern" "$src/$layer" || true)
done
while IFS= read -r line; do
  bad "mpi.h outside decomp, app and io's parallel writers: $line"
done < <(grep -rln '#include <mpi.h>' "$src" | grep -vE "^$src/(decomp|app)/" |
         grep -vE "^$src/io/(output|checkpoint|agreed_write)\.hpp$|^$src/io/(hdf5_output|checkpoint|h5)\.cpp$" || true)
# Every folder of src/ is a layer.
for d in "$src"/*/; do
  d=$(basename "$d")
  [[ " ${order[*]} " == *" $d "* ]] || bad "folder $d is in no layer"
done
chain=$(printf " -> %s" "${order[@]}"); ((fail == 0)) && echo "ok: ${chain:4}: no include runs back up; mpi.h only in decomp, app and io's writers"
exit $fail
