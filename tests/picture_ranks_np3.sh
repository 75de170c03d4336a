#!/usr/bin/env bash
# End to end: drape.png, drawn by rank 0 from the samples' positions their
# owners send, is the same file on 1, 2 and 3 ranks: a box drape under AMRC
# (coarse cells' particles filled along grid lines) and the Cusick drape
# test, whose report.json figures (from the ranks' shadow rasters or-ed
# together) must agree too.
# Usage: picture_ranks_np3.sh DRAPE MPIEXEC SOURCE_DIR WORK_DIR
set -euo pipefail
drape=$1 mpiexec=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
figures() { report "$1" '"%r %d %r %r %r" % (r["drape_coefficient"], r["drape_nodes"], r["drape_areas"]["shadow"], r["drape_areas"]["specimen"], r["drape_areas"]["disc"])'; }
box=(--config "$src/run/scenes/small-box.toml" --set "cloth.particles=[33,33]" --set cloth.tile=8
     --set solver.steps=40 --set output.every=40 --set amrc.enabled=true --set amrc.max_level=2 --set amrc.every=2)
cusick=(--config "$src/run/scenes/cusick.toml" --set solver.steps=150 --set 'solver.preconditioner="jacobi"'
        --set cloth.tile=16)
for scene in box cusick; do
  declare -n args=$scene
  OMP_NUM_THREADS=1 "$drape" "${args[@]}" --quiet --output "$work/$scene-1"
  if [[ $scene == box ]]; then
    (( $(report "$work/box-1" 'r["amrc"]["coarsened"]') > 0 )) ||
      { echo "box: no coarse cells: the case does not cover filling inactive particles"; exit 1; }
  fi
  for n in 2 3; do
    OMP_NUM_THREADS=1 "$mpiexec" -n $n "$drape" "${args[@]}" --quiet --output "$work/$scene-$n"
    cmp "$work/$scene-1/drape.png" "$work/$scene-$n/drape.png" ||
      { echo "$scene: drape.png differs between 1 and $n ranks"; exit 1; }
    if [[ $scene == cusick ]]; then
      one=$(figures "$work/cusick-1") many=$(figures "$work/cusick-$n")
      [[ $one == "$many" ]] || { echo "cusick: drape figures differ: 1 rank $one, $n ranks $many"; exit 1; }
    fi
    echo "$scene: drape.png the same on 1 and $n ranks"
  done
done
echo "cusick: $(figures "$work/cusick-1") on 1, 2 and 3 ranks"
