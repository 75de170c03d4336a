#!/usr/bin/env bash
# AMRC in the drape program: with adaptation on (uneven lists, hanging
# particles), the state checksum is the same for every thread count and
# schedule; the total mass is the finest mesh's; the mesh really changes;
# a run stopped and restarted from its checkpoint (tree included) ends
# where the uninterrupted one does, also when the first part ran on 2 ranks
# or the second (several ranks against one: ranks_agree.sh).
# Usage: amrc_runs.sh DRAPE MPIEXEC SOURCE_DIR WORK_DIR
set -euo pipefail
drape=$1 mpiexec=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
scene=(--config "$src/run/scenes/small-box.toml" --set "cloth.particles=[33,33]" --set cloth.tile=8
       --set solver.steps=60 --set output.every=10 --set output.picture=false --quiet
       --set amrc.enabled=true --set amrc.max_level=2 --set amrc.every=2)
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

"$drape" "${scene[@]}" --threads 1 --output "$work/ref"
ref=$(sum "$work/ref")
min=$(report "$work/ref" 'r["particles_active"]["min"]')
max=$(report "$work/ref" 'r["particles_active"]["max"]')
(( min < max )) || { echo "FAIL: the mesh never changed (active particles $min..$max)"; exit 1; }
echo "ok active particles $min..$max of 1089"
mean=$(report "$work/ref" 'r["particles_active"]["mean"]')
python3 -c "import sys; sys.exit(not ($min < $mean < $max))" ||
  { echo "FAIL: the iteration-weighted mean $mean is not strictly inside $min..$max"; exit 1; }
echo "ok mean active particles per CG iteration $mean"
"$drape" --config "$src/run/scenes/small-box.toml" --set "cloth.particles=[33,33]" --set solver.steps=1 \
  --set output.picture=false --quiet --output "$work/finest"
python3 - "$work/ref/report.json" "$work/finest/report.json" <<'PY'
import json, sys
a, b = (json.load(open(p))["total_mass"] for p in sys.argv[1:3])
assert abs(a - b) <= 1e-12 * b, f"FAIL: mass {a} with AMRC, {b} on the finest mesh"
print(f"ok total mass {a} equals the finest mesh's to 1e-12")
PY
for threads in 1 2 3; do
  for schedule in active-lists static dynamic guided; do
    "$drape" "${scene[@]}" --threads $threads --set parallel.schedule=$schedule --output "$work/t$threads-$schedule"
    [[ $(sum "$work/t$threads-$schedule") == "$ref" ]] ||
      { echo "FAIL: $threads thread(s), $schedule: $(sum "$work/t$threads-$schedule") vs $ref"; exit 1; }
  done
done
echo "ok same checksum for 1-3 threads x 4 schedules: $ref"

"$drape" "${scene[@]}" --set solver.steps=31 --set output.checkpoint_every=31 --threads 2 --output "$work/part"
cp -r "$work/part" "$work/part1"
"$drape" --restart "$work/part/checkpoint.h5" --set solver.steps=60 --threads 1 --quiet
[[ $(sum "$work/part") == "$ref" ]] || { echo "FAIL: restart with AMRC: $(sum "$work/part") vs $ref"; exit 1; }
part_mean=$(report "$work/part" 'r["particles_active"]["mean"]')
[[ $part_mean == "$mean" ]] ||
  { echo "FAIL: the mean active particles after a restart: $part_mean vs $mean"; exit 1; }
h5diff "$work/ref/drape.h5" "$work/part/drape.h5" /frames /frames || { echo "FAIL: frames differ after restart"; exit 1; }
echo "ok stopped at 31, restarted: the same state and frames"

OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$drape" "${scene[@]}" --set solver.steps=31 --set output.checkpoint_every=31 \
  --output "$work/part2"
"$drape" --restart "$work/part2/checkpoint.h5" --set solver.steps=60 --threads 2 --quiet
[[ $(sum "$work/part2") == "$ref" ]] || { echo "FAIL: 2 ranks, then 1 from the checkpoint: $(sum "$work/part2") vs $ref"; exit 1; }
h5diff "$work/ref/drape.h5" "$work/part2/drape.h5" /frames /frames || { echo "FAIL: frames differ (2 ranks, restart)"; exit 1; }
echo "ok 31 steps on 2 ranks, restarted on 1: the same state and frames"
# 2 ranks go on from the 1-rank checkpoint: each reads its own tiles' and
# ghosts' particles, the tree whole.
"$mpiexec" -n 2 "$drape" --restart "$work/part1/checkpoint.h5" --set solver.steps=60 --threads 1 --quiet
[[ $(sum "$work/part1") == "$ref" ]] || { echo "FAIL: 1 rank, then 2 from the checkpoint: $(sum "$work/part1") vs $ref"; exit 1; }
h5diff "$work/ref/drape.h5" "$work/part1/drape.h5" /frames /frames || { echo "FAIL: frames differ (restart on 2 ranks)"; exit 1; }
echo "ok 31 steps on 1 rank, restarted on 2: the same state and frames"

# amrc.start_spacing with AMRC: a new run starts on leaves that wide (level 2
# here: 9 x 9 of the 33 x 33 particles), a restart on its checkpoint's tree.
coarse=(--config "$src/run/scenes/small-box.toml" --set "cloth.particles=[33,33]" --set cloth.tile=8
        --set output.picture=false --set amrc.enabled=true --set amrc.max_level=2 --set amrc.every=2
        --set amrc.start_spacing=0.13 --set solver.steps=20)
"$drape" "${coarse[@]}" --threads 2 --output "$work/coarse" > "$work/coarse.out"
first=$(grep -m1 '^step' "$work/coarse.out")
[[ $first =~ particles\ 81\  ]] || { echo "FAIL: the first step did not run on the 9 x 9 mesh: $first"; exit 1; }
"$drape" "${coarse[@]}" --set solver.steps=10 --set output.checkpoint_every=10 --quiet --output "$work/coarse-part"
"$drape" --restart "$work/coarse-part/checkpoint.h5" --set solver.steps=20 --quiet
[[ $(sum "$work/coarse-part") == $(sum "$work/coarse") ]] ||
  { echo "FAIL: start_spacing, restarted: $(sum "$work/coarse-part") vs $(sum "$work/coarse")"; exit 1; }
echo "ok start_spacing 0.13: the first step on 81 particles; a restart keeps its tree"

# The multigrid preconditioner with AMRC (levels over hanging particles and
# coarse leaves, rebuilt as the mesh changes): the same checksum on 1 and 3
# threads and two schedules, and a run restarted from its checkpoint ends
# where the uninterrupted one does (the V-cycle is rebuilt at each step's
# first solve, so a restart rebuilds where the first run did).
mg=("${scene[@]}" --set 'solver.preconditioner="multigrid"')
"$drape" "${mg[@]}" --threads 1 --output "$work/mg"
mgref=$(sum "$work/mg")
python3 - "$work/mg/report.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
assert r["preconditioner"] == "multigrid", r["preconditioner"]
levels = r["multigrid"]
assert len(levels) >= 2 and levels[0]["cycles"] > 0, f"FAIL: no V-cycle ran: {levels}"
print(f"ok multigrid with AMRC: {len(levels)} levels, {levels[0]['cycles']} V-cycles")
PY
for run in "3 active-lists" "3 dynamic" "2 static"; do
  set -- $run
  "$drape" "${mg[@]}" --threads "$1" --set parallel.schedule="$2" --output "$work/mg-$1-$2"
  [[ $(sum "$work/mg-$1-$2") == "$mgref" ]] ||
    { echo "FAIL: multigrid, $1 thread(s), $2: $(sum "$work/mg-$1-$2") vs $mgref"; exit 1; }
done
"$drape" "${mg[@]}" --set solver.steps=31 --set output.checkpoint_every=31 --threads 2 --output "$work/mg-part"
"$drape" --restart "$work/mg-part/checkpoint.h5" --set solver.steps=60 --threads 1 --quiet
[[ $(sum "$work/mg-part") == "$mgref" ]] || { echo "FAIL: multigrid, restarted: $(sum "$work/mg-part") vs $mgref"; exit 1; }
echo "ok multigrid with AMRC: the same checksum on 1-3 threads and after a restart: $mgref"
