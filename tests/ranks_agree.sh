#!/usr/bin/env bash
# End to end: the drape program on 1 rank and on 2 ranks (mpiexec -n 2) gives
# the same state checksum and the same drape.h5 datasets, bit for bit.
# Usage: ranks_agree.sh DRAPE MPIEXEC SOURCE_DIR WORK_DIR
set -euo pipefail
drape=$1 mpiexec=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
args=(--config "$src/run/scenes/small-box.toml" --set "cloth.particles=[17,17]"
      --set solver.steps=6 --set output.every=3 --quiet)
OMP_NUM_THREADS=1 "$drape" "${args[@]}" --output "$work/one"
OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$drape" "${args[@]}" --output "$work/two"
sum() { grep -o '"state_checksum": "[0-9a-f]*"' "$1/report.json"; }
one=$(sum "$work/one") two=$(sum "$work/two")
[[ -n $one && $one == "$two" ]] || { echo "checksums differ: 1 rank $one, 2 ranks $two"; exit 1; }
grep -q '"ranks": 2' "$work/two/report.json" || { echo "the 2-rank report does not say 2 ranks"; exit 1; }
h5diff "$work/one/drape.h5" "$work/two/drape.h5" /frames /frames || { echo "drape.h5 frames differ"; exit 1; }
echo "1 and 2 ranks agree: $one"
