#!/usr/bin/env bash
# End to end: the drape program on 1, 2 and 4 ranks (4 oversubscribed), the
# cloth split into 25 tiles by METIS, gives the same state checksum and the
# same drape.h5 datasets and drape.png, bit for bit, with either solver; and with AMRC on,
# where the 2- and 4-rank runs must have rebalanced (tiles migrated) at
# least once. The Newton case runs Jacobi with the halving line search and
# the KES reversal and air drag on, so the step-start anchors of the ring's
# elements read the ghosts too; the slope case is it with Newton's slope
# line search, whose slope is a sum over ranks (its path must differ from
# the halving one's), and the adaptive
# forcing, whose linear tolerance follows the cost's fall; the kinks case is it with Newton's band active set,
# whose re-solves follow those slopes and each element's own branches, the
# ring's too. The other cases run the default preconditioner ("auto": the
# multigrid on the sequence case's finest mesh, Jacobi with AMRC). The
# amrc_speed case adds amrc.coarsen_speed, whose speeds each rank computes
# for its own particles only: it must hold back some merges. The amrc_edges
# case starts on coarse deflection leaves, so that leaves across the box's
# edges cut into it and split for that (the inside mask, which each rank
# computes for its own particles): it must do so at least once. The
# multigrid case is the Newton case with the multigrid preconditioner and
# the slope line search (self-contact and friction on, as by default: its
# state must differ from a frictionless run's), whose finest level
# each rank builds and runs on its own rows of K and a ring of others' (level
# 1's rows and right-hand side gathered; the levels below whole on every
# rank); it
# runs on 2 (with 2 threads a rank), 3 and 4 ranks, its
# V-cycles must have run, the bytes each rank reports gathered
# (report.json multigrid_gathered) must be level 1's rows' and blocks', the
# power iteration's vectors and level 1's right-hand side's, and one
# rank's none, and a 2-rank run stopped at step 20 and continued
# on 3 ranks must end in the same state.
# The amrc_multigrid case is the amrc case on the multigrid: hanging
# particles fold into K's rows of their ends, which may be other ranks'
# particles; it runs on 2, 3 and 4 ranks, must have run V-cycles on an
# adapting mesh and rebalanced on several ranks.
# Usage: ranks_agree.sh DRAPE MPIEXEC SOURCE_DIR WORK_DIR [CASES]
# (CASES: some of the cases below, space-separated; default all but amrc_edges,
# kinks, multigrid and amrc_multigrid, which ctest runs as tests of their own)
set -euo pipefail
drape=$1 mpiexec=$2 src=$3 work=$4 cases=${5:-"newton slope cg amrc amrc_speed sequence"}
rm -rf "$work" && mkdir -p "$work"
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
# The final state's kinks (report.json zigzag), counted by each rank over its own particles.
zz() { report "$1" '"%d %d" % (r["zigzag"]["pairs"], r["zigzag"]["zigzags"])'; }
amrc=(--set amrc.enabled=true --set amrc.max_level=2 --set amrc.every=2 --set solver.steps=60)
# A cloth let down onto the floor just inside the coarse mesh's contact layer
# (half its cell diagonal, 44.2 mm): at rest on that mesh after a few steps,
# then split (the drape over the box would take thousands of steps to rest),
# and at rest on the finest mesh a few steps later.
sequence=(--set amrc.start_spacing=0.07 --set solver.rest_speed=0.03 --set amrc.stage_drag=2
          --set 'obstacle.shape="none"' --set cloth.height=0.044)
jacobi=(--set 'solver.preconditioner="jacobi"')
edges=(--set 'amrc.indicator="deflection"' --set amrc.refine=0.5 --set amrc.coarsen=0.1
       --set amrc.start_spacing=0.05 --set solver.steps=120 --set output.every=40)
for method in $cases; do
  args=(--config "$src/run/scenes/small-box.toml" --set "cloth.particles=[33,33]" --set cloth.tile=8
        --set solver.steps=40 --set output.every=10 --quiet)
  case $method in
    amrc) args+=("${amrc[@]}") ;;
    amrc_speed) args+=("${amrc[@]}" --set amrc.coarsen_speed=0.01) ;;
    amrc_edges) args+=("${amrc[@]}" "${edges[@]}") ;;
    amrc_multigrid) args+=("${amrc[@]}" --set 'solver.preconditioner="multigrid"') ;;
    sequence) args+=("${sequence[@]}") ;;
    newton) args+=(--set solver.method=newton "${jacobi[@]}" --set solver.slope_line_search=false) ;;
    slope) args+=(--set solver.method=newton "${jacobi[@]}" --set solver.slope_line_search=true
                  --set solver.adaptive_forcing=true) ;;
    kinks) args+=(--set solver.method=newton "${jacobi[@]}" --set solver.slope_line_search=false
                  --set solver.band_active_set=true) ;;
    multigrid) args+=(--set solver.method=newton --set 'solver.preconditioner="multigrid"') ;;
    *) args+=(--set solver.method=$method) ;;
  esac
  if [[ $method == newton || $method == slope || $method == kinks || $method == multigrid ]]; then
    args+=(--set cloth.bend_reversal=5 --set cloth.shear_reversal=3 --set cloth.stretch_reversal=2 --set solver.drag=3 --set cloth.height=0.43)
  fi
  OMP_NUM_THREADS=1 "$drape" "${args[@]}" --output "$work/$method-1"
  counts="2 4" threads=1
  [[ $method == multigrid || $method == amrc_multigrid ]] && counts="2 3 4"
  for n in $counts; do
    threads=1
    [[ $method == multigrid && $n == 2 ]] && threads=2
    # Passive waits: 2 ranks of 2 spinning threads on 2 shared cores crawl.
    OMP_WAIT_POLICY=passive OMP_NUM_THREADS=$threads "$mpiexec" -n $n "$drape" "${args[@]}" --output "$work/$method-$n"
    one=$(sum "$work/$method-1") many=$(sum "$work/$method-$n")
    [[ -n $one && $one == "$many" ]] || { echo "$method: checksums differ: 1 rank $one, $n ranks $many"; exit 1; }
    [[ $(field "$work/$method-$n" ranks) == "$n" ]] || { echo "the report does not say $n ranks"; exit 1; }
    [[ $(report "$work/$method-$n" 'r["cpu_seconds"] > 0') == true ]] || { echo "$method: the $n-rank report has no CPU time"; exit 1; }
    [[ $(zz "$work/$method-1") == $(zz "$work/$method-$n") ]] ||
      { echo "$method: zigzag counts (pairs, zigzags) differ: 1 rank $(zz "$work/$method-1"), $n ranks $(zz "$work/$method-$n")"; exit 1; }
    h5diff "$work/$method-1/drape.h5" "$work/$method-$n/drape.h5" /frames /frames ||
      { echo "$method: drape.h5 frames differ between 1 and $n ranks"; exit 1; }
    cmp -s "$work/$method-1/drape.png" "$work/$method-$n/drape.png" ||
      { echo "$method: drape.png differs between 1 and $n ranks"; exit 1; }
    if [[ $method == amrc || $method == amrc_multigrid ]]; then
      moved=$(report "$work/$method-$n" 'sum(b["tiles_moved"] for b in r["rebalances"])')
      (( moved > 0 )) || { echo "$method: no tile migrated on $n ranks: the test does not cover a rebalance"; exit 1; }
      echo "$method: $n ranks rebalanced, $moved tile move(s) in all"
    fi
    if [[ $method == multigrid ]]; then
      # No rank receives K whole: at a build, each receives level 1's rows (8 bytes a row,
      # 76 a block; under half K's) and the power iteration's vector at its start and each
      # step (24 bytes a particle; 12 steps cold, 3 warm); at a V-cycle, level 1's
      # right-hand side (24 bytes a level-1 particle); one rank gathers nothing.
      formula='(lambda g, l, c, b: (lambda one, v: g["per_build_bytes"] - one in (4 * v, 13 * v)
        and (g["builds_bytes"] - b * one) % v == 0 and 4 * b * v <= g["builds_bytes"] - b * one <= 13 * b * v
        and 2 * one < 76 * l["blocks"] + 8 * l["particles"]
        and g["per_cycle_bytes"] == 24 * c["particles"] and g["cycles_bytes"] == l["cycles"] * 24 * c["particles"]
        and b > 0)(76 * c["blocks"] + 8 * c["particles"], 24 * l["particles"]))(r["multigrid_gathered"], r["multigrid"][0],
        r["multigrid"][1], r["multigrid_gathered"]["builds"])'
      [[ $(report "$work/$method-$n" "$formula") == true ]] ||
        { echo "multigrid: $n ranks' gathered bytes $(field "$work/$method-$n" multigrid_gathered) are not the rows' and blocks'"; exit 1; }
      [[ $(report "$work/$method-1" 'sorted(set(v for k, v in r["multigrid_gathered"].items() if k.endswith("bytes")))') == "[0]" ]] ||
        { echo "multigrid: one rank gathered $(field "$work/$method-1" multigrid_gathered)"; exit 1; }
    fi
    echo "$method: 1 and $n ranks agree: $one"
  done
  (( $(field "$work/$method-1" iterations) > 0 )) || { echo "$method: no iterations ran"; exit 1; }
  if [[ $method == slope && -d $work/newton-1 ]]; then
    [[ $(sum "$work/slope-1") != $(sum "$work/newton-1") ]] ||
      { echo "slope: the same state as the halving line search: the case does not reach the slope search"; exit 1; }
  fi
  if [[ $method == multigrid ]]; then
    cycles=$(report "$work/multigrid-4" 'r["multigrid"][0]["cycles"] if r["multigrid"] else 0')
    (( cycles > 0 )) || { echo "multigrid: no V-cycle ran on 4 ranks"; exit 1; }
    echo "multigrid: $cycles V-cycles on 4 ranks"
    # Stopped at step 20 on 2 ranks, continued on 3: the uninterrupted run's state.
    OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$drape" "${args[@]}" --set solver.steps=20 --set output.checkpoint_every=20 \
      --output "$work/multigrid-restart"
    OMP_NUM_THREADS=1 "$mpiexec" -n 3 "$drape" --restart "$work/multigrid-restart/checkpoint.h5" --set solver.steps=40 --quiet
    [[ $(sum "$work/multigrid-restart") == $(sum "$work/multigrid-1") ]] ||
      { echo "multigrid: 2 ranks to step 20, then 3 ranks: $(sum "$work/multigrid-restart"), not $(sum "$work/multigrid-1")"; exit 1; }
    echo "multigrid: restarted on 3 ranks from 2 ranks' step 20: the same state"
    # Friction (on by default) held the cloth on the box during the run.
    OMP_NUM_THREADS=1 "$drape" "${args[@]}" --set obstacle.friction=0 --set obstacle.floor_friction=0 \
      --output "$work/multigrid-frictionless" >/dev/null
    [[ $(sum "$work/multigrid-1") != $(sum "$work/multigrid-frictionless") ]] ||
      { echo "multigrid: the same state as without friction: the case does not cover friction"; exit 1; }
    echo "multigrid: friction changed the state (frictionless $(sum "$work/multigrid-frictionless"))"
  fi
  if [[ $method == kinks ]]; then
    "$drape" "${args[@]}" --set solver.band_active_set=false --output "$work/kinks-off" >/dev/null
    [[ $(sum "$work/kinks-1") != $(sum "$work/kinks-off") ]] ||
      { echo "kinks: the same state as without the active set: the case does not reach a re-solve"; exit 1; }
  fi
  if [[ $method == amrc_multigrid ]]; then
    cycles=$(report "$work/$method-3" 'r["multigrid"][0]["cycles"] if r["multigrid"] else 0')
    adapted=$(report "$work/$method-1" 'r["amrc"]["refined"] > 0 and r["particles_active"]["min"] < r["particles_active"]["max"]')
    (( cycles > 0 )) && [[ $adapted == true ]] ||
      { echo "amrc_multigrid: $cycles V-cycles on 3 ranks, the mesh adapted: $adapted"; exit 1; }
    echo "amrc_multigrid: $cycles V-cycles on 3 ranks on an adapting mesh"
  fi
  if [[ $method == amrc_speed ]]; then
    merges() { report "$1" 'r["amrc"]["coarsened"]'; }
    held=$(merges "$work/amrc_speed-1") free=$(merges "$work/amrc-1")
    (( held < free )) || { echo "amrc_speed: $held merges, not fewer than $free without the speed condition"; exit 1; }
    echo "amrc_speed: $held merges against $free without the speed condition"
  fi
  if [[ $method == amrc_edges ]]; then
    cut=$(report "$work/$method-1" 'r["amrc"]["refined_inside"]')
    (( cut > 0 )) || { echo "amrc_edges: no leaf split for cutting into the box: the case does not cover the inside mask"; exit 1; }
    echo "amrc_edges: $cut leaf split(s) for cutting into the box"
  fi
  if [[ $method == sequence ]]; then
    stages=$(report "$work/$method-1" '" ".join("%d@%d" % (g["level"], g["from_step"]) for g in r["stages"])')
    [[ $stages =~ ^1@0\ 0@([0-9]+)$ ]] && (( BASH_REMATCH[1] >= 2 )) ||
      { echo "sequence: stages $stages, expected level 1 from step 0, then level 0 after a few steps at rest"; exit 1; }
    # Rest on the coarse mesh is not rest on the finest: the run goes on after the split.
    split=${BASH_REMATCH[1]} steps=$(field "$work/$method-1" steps)
    (( steps >= split + 3 )) || { echo "sequence: the run ended at step $steps, right after the split at step $split"; exit 1; }
    echo "sequence: stages $stages, $steps steps"
    # Past the split the halo is the finest mesh's (ghosts 4 intervals out,
    # the ring 2), not the coarse stage's (8, 4); a restart there ends alike.
    widths=$(report "$work/$method-4" '"%d %d" % (r["decomposition"]["ghost_width"], r["decomposition"]["ring_width"])')
    [[ $widths == "4 2" ]] || { echo "sequence: the halo's widths on the finest stage are $widths, not 4 2"; exit 1; }
    at=$((split + 2))
    OMP_WAIT_POLICY=passive OMP_NUM_THREADS=1 "$mpiexec" -n 4 "$drape" "${args[@]}" --set solver.steps=$at \
      --set output.checkpoint_every=$at --output "$work/$method-part"
    OMP_WAIT_POLICY=passive OMP_NUM_THREADS=1 "$mpiexec" -n 4 "$drape" --restart "$work/$method-part/checkpoint.h5" \
      --set solver.steps=$steps --quiet
    [[ $(sum "$work/$method-part") == $(sum "$work/$method-4") ]] ||
      { echo "sequence: restarted past the split on 4 ranks: $(sum "$work/$method-part") vs $(sum "$work/$method-4")"; exit 1; }
    echo "sequence: past the split the halo's widths $widths; restarted there on 4 ranks, the same state"
  fi
done
