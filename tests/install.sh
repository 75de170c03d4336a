#!/usr/bin/env bash
# cmake --install gives a usable drape: a downstream CMake project finds it with
# find_package(drape), builds against drape::core and runs; the installed
# program, run from elsewhere, reads the fabrics installed next to it.
# Usage: install.sh CMAKE BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
cmake=$1 build=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work/elsewhere"
prefix=$work/prefix

"$cmake" --install "$build" --prefix "$prefix" >"$work/install.log"
for f in bin/drape lib/cmake/drape/drapeConfig.cmake lib/cmake/drape/drapeConfigVersion.cmake \
         lib/cmake/drape/FindMETIS.cmake share/drape/data/kes/denim-A.toml include/drape/solver/scene.hpp; do
  [[ -e $prefix/$f ]] || { echo "FAIL: the install has no $f"; exit 1; }
done

"$cmake" -S "$src/tests/downstream" -B "$work/downstream" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=Release >"$work/downstream.log" || { cat "$work/downstream.log"; echo "FAIL: configure"; exit 1; }
"$cmake" --build "$work/downstream" >>"$work/downstream.log" 2>&1 || { cat "$work/downstream.log"; echo "FAIL: build"; exit 1; }
[[ $("$work/downstream/downstream") == newton ]] || { echo "FAIL: the downstream program"; exit 1; }
echo "ok: find_package(drape), drape::core linked and run"

# A fabric only the install has: found only if the program looks next to
# itself (the build-time source path has no such file).
cp "$prefix/share/drape/data/kes/denim-A.toml" "$prefix/share/drape/data/kes/installed-only.toml"
cd "$work/elsewhere"
env -u DRAPE_DATA "$prefix/bin/drape" --dry-run --set cloth.fabric=installed-only >"$work/dry-run.toml" \
  || { echo "FAIL: the installed drape does not find its data"; exit 1; }
grep -q '^fabric = "installed-only"' "$work/dry-run.toml" || { echo "FAIL: dry-run output"; exit 1; }
echo "ok: the installed drape reads $prefix/share/drape/data"
rm -rf "$work"
