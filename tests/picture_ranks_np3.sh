#!/usr/bin/env bash
# End to end: drape.png, drawn by rank 0 from the samples' positions their
# owners send, is the same file on 1, 2 and 3 ranks: a box drape under AMRC
# (coarse cells' particles filled along grid lines) and the Cusick drape
# test, whose report.json figures (from the ranks' shadow rasters or-ed
# together) must agree too; and rank 0 receives only the positions the
# picture samples (report.json's picture_positions), not the whole cloth.
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
# A long strip of 801 x 9 particles: the picture samples 268 of its 801
# rows, and rank 0 receives their positions alone, on any number of ranks.
strip=(--config "$src/run/scenes/small-box.toml" --set "cloth.particles=[801,9]" --set "cloth.size=[1.6,0.016]"
       --set cloth.tile=40 --set solver.steps=1 --set output.every=0)
for n in 1 2 3; do
  OMP_NUM_THREADS=1 "$mpiexec" -n $n "$drape" "${strip[@]}" --quiet --output "$work/strip-$n"
  got=$(field "$work/strip-$n" picture_positions)
  (( got > 0 && got <= 268 * 9 )) ||
    { echo "strip: rank 0 received $got positions on $n ranks, not the 268 x 9 sampled"; exit 1; }
  cmp "$work/strip-1/drape.png" "$work/strip-$n/drape.png" || { echo "strip: drape.png differs on $n ranks"; exit 1; }
done
echo "strip: rank 0 received $got of the 801 x 9 positions on 1, 2 and 3 ranks"
