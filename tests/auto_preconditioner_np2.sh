#!/usr/bin/env bash
# solver.preconditioner = "auto" (the default): with AMRC every adapted mesh
# takes the multigrid from the threshold on, and Jacobi below it, on one
# rank as on two, and the two end in the same state. Grid sequencing (AMRC
# off) switches on the first mesh at or above the threshold, on one rank and
# on two alike (self-contact on: its blocks across ranks).
# Usage: auto_preconditioner_np2.sh DRAPE MPIEXEC SOURCE_DIR WORK_DIR
set -euo pipefail
drape=$1 mpiexec=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
scene=(--config "$src/run/scenes/small-box.toml" --set "cloth.particles=[25,25]" --set solver.steps=3 --set cloth.height=0.401
       --set output.picture=false --quiet --set amrc.enabled=true --set amrc.max_level=2 --set amrc.every=3
       --set 'solver.preconditioner="auto"')
builds() { report "$1" 'r["multigrid_gathered"]["builds"]'; }
fail() { echo "FAIL: $*"; exit 1; }

# The threshold above the mesh's 625 particles: Jacobi; at 1: the multigrid.
for at in 1000 1; do
  OMP_NUM_THREADS=1 "$drape" "${scene[@]}" --set solver.multigrid_particles=$at --output "$work/one-$at" \
    > "$work/one-$at.out" 2>&1 || { cat "$work/one-$at.out"; fail "one rank with AMRC, auto, threshold $at"; }
  [[ $(report "$work/one-$at" 'r["iterations"] > 0') == true ]] || fail "one rank with AMRC: no iterations"
  OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$drape" "${scene[@]}" --set solver.multigrid_particles=$at --output "$work/two-$at" \
    > "$work/two-$at.out" 2>&1 || { cat "$work/two-$at.out"; fail "two ranks with AMRC, auto, threshold $at"; }
  [[ $(builds "$work/two-$at") == $(builds "$work/one-$at") ]] ||
    fail "threshold $at: multigrid builds $(builds "$work/two-$at") on two ranks, $(builds "$work/one-$at") on one"
  [[ $(sum "$work/two-$at") == $(sum "$work/one-$at") ]] || fail "two ranks with AMRC do not end in one rank's state"
done
[[ $(builds "$work/one-1000") == 0 ]] || fail "AMRC below the threshold: multigrid builds $(builds "$work/one-1000")"
(( $(builds "$work/one-1") > 0 )) || fail "AMRC above the threshold: no multigrid build"

# Grid sequencing from 9 x 9 (81 particles) to 17 x 17 (289), ending there
# (amrc.last_level): Jacobi on the first mesh, the multigrid on the second.
seq=(--set "cloth.particles=[33,33]" --set cloth.tile=8 --set amrc.start_spacing=0.13 --set amrc.last_level=1 --set solver.wall_limit=0
     --set output.picture=false --quiet --set 'solver.preconditioner="auto"' --set solver.multigrid_particles=200)
OMP_NUM_THREADS=1 "$drape" "${seq[@]}" --output "$work/seq" > "$work/seq.out" 2>&1 ||
  { cat "$work/seq.out"; fail "sequencing, auto"; }
got=$(report "$work/seq" '[(s["level"], s["particles"], s["stage_preconditioner"], s["stage_multigrid_builds"] > 0) for s in r["stages"]] + [r["final_level"], r["at_rest"]]')
[[ $got == '[[2, 81, "jacobi", false], [1, 289, "multigrid", true], 1, true]' ]] || fail "sequencing stages: $got"
OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$drape" "${seq[@]}" --output "$work/seq2" > "$work/seq2.out" 2>&1 ||
  { cat "$work/seq2.out"; fail "sequencing on two ranks, auto"; }
[[ $(builds "$work/seq2") -gt 0 ]] || fail "sequencing on two ranks: no multigrid built"
[[ $(sum "$work/seq2") == $(sum "$work/seq") ]] || fail "sequencing on two ranks does not end in one rank's state"
echo "auto_preconditioner: the multigrid from the threshold on, with AMRC and without, on one rank and two alike"
