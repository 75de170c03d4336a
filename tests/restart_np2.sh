#!/usr/bin/env bash
# Restart equality: a run stopped at step k (by its step count, or by SIGTERM
# at an unknown point) and continued with `drape --restart` on another number
# of ranks and threads ends with the same state checksum and the same drape.h5
# frames as the run that was never interrupted.
# Usage: restart_np2.sh DRAPE MPIEXEC SOURCE_DIR WORK_DIR
set -euo pipefail
drape=$1 mpiexec=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
scene=(--config "$src/run/scenes/small-box.toml" --set "cloth.particles=[17,17]" --set output.every=5
       --set output.picture=false --quiet)
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
same() {  # same() REFERENCE CANDIDATE LABEL
  # A run the wall limit cut short (oversubscribed threads can take minutes)
  # ends elsewhere: say so rather than report a checksum that differs.
  [[ $(field "$2" steps) == "$(field "$1" steps)" ]] || {
    echo "FAIL $3: ended at step $(field "$2" steps), not $(field "$1" steps)" \
      "(stopped by the wall limit: $(field "$2" stopped_by_wall_limit))"; exit 1; }
  [[ $(sum "$1") == "$(sum "$2")" ]] || { echo "FAIL $3: $(sum "$1") vs $(sum "$2")"; exit 1; }
  h5diff "$1/drape.h5" "$2/drape.h5" /frames /frames || { echo "FAIL $3: drape.h5 frames differ"; exit 1; }
  echo "ok $3: $(sum "$2")"
}

# The reference: 40 steps in one go, 1 rank x 1 thread.
OMP_NUM_THREADS=1 "$drape" "${scene[@]}" --set solver.steps=40 --output "$work/ref"

# 2 ranks x 1 thread stop at step 20 (checkpoints at 7, 14, 20), then
# 1 rank x 2 threads continue in the same directory (the default).
OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$drape" "${scene[@]}" --set solver.steps=20 \
  --set output.checkpoint_every=7 --output "$work/a"
[[ $(field "$work/a" steps) == 20 ]] || { echo "FAIL: the first part did not run 20 steps"; exit 1; }
"$drape" --restart "$work/a/checkpoint.h5" --set solver.steps=40 --threads 2 --quiet
[[ $(field "$work/a" restarted_from_step) == 20 ]] || { echo "FAIL: the report does not name step 20"; exit 1; }
same "$work/ref" "$work/a" "2 ranks -> 1 rank x 2 threads"

# 1 rank x 2 threads stop at step 13, then 2 ranks x 1 thread continue
# (2 x 2 would oversubscribe 2 cores with spinning OpenMP threads).
OMP_NUM_THREADS=2 "$drape" "${scene[@]}" --set solver.steps=13 --set output.checkpoint_every=13 \
  --output "$work/b"
OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$drape" --restart "$work/b/checkpoint.h5" --set solver.steps=40 --quiet
same "$work/ref" "$work/b" "1 rank x 2 threads -> 2 ranks x 1 thread"

# The multigrid on both of its builds on several ranks (the finest level
# divided over the ranks, and K gathered whole on every rank: the reference
# path): 2 ranks stop at step 20, 3 ranks continue. Each step's first build
# starts its power iterations cold, so nothing the V-cycle kept is missing
# from the checkpoint. (Small meshes take Jacobi under "auto": forced here.)
for divided in true false; do
  mg=("${scene[@]}" --set 'solver.preconditioner="multigrid"' --set solver.multigrid_divided=$divided)
  OMP_NUM_THREADS=1 "$drape" "${mg[@]}" --set solver.steps=40 --output "$work/mg-ref-$divided"
  [[ $(report "$work/mg-ref-$divided" 'r["multigrid_gathered"]["builds"] > 0 or len(r["multigrid"]) > 1') == true ]] ||
    { echo "FAIL: the multigrid did not run"; exit 1; }
  OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$drape" "${mg[@]}" --set solver.steps=20 --set output.checkpoint_every=20 \
    --output "$work/mg-$divided"
  OMP_NUM_THREADS=1 "$mpiexec" -n 3 "$drape" --restart "$work/mg-$divided/checkpoint.h5" --set solver.steps=40 --quiet
  same "$work/mg-ref-$divided" "$work/mg-$divided" "multigrid (divided=$divided), 2 ranks -> 3 ranks"
done

# SIGTERM at an unknown point of a run that cannot end first: exit 0, the
# step in progress rolled back, a checkpoint of the last finished step;
# continued to the reference's 300 steps, it ends where the uninterrupted
# run ends. The signal goes once the first checkpoint (step 5) is there; the
# run was given no step limit it could reach, so a signal that did not land
# (or landed after step 300, seconds late) fails the test.
long=(--config "$src/run/scenes/small-box.toml" --set "cloth.particles=[25,25]" --set output.every=0
      --set output.picture=false --quiet)
OMP_NUM_THREADS=1 "$drape" "${long[@]}" --set solver.steps=300 --output "$work/long-ref"
# (The wall limit bounds a run the signal missed; one it reaches stops long before.)
OMP_NUM_THREADS=1 "$drape" "${long[@]}" --set solver.steps=100000 --set output.checkpoint_every=5 \
  --set solver.wall_limit=30 --output "$work/sig" > "$work/sig.out" 2>&1 &
pid=$!
for _ in $(seq 600); do [[ -e $work/sig/checkpoint.h5 ]] && break; sleep 0.05; done
[[ -e $work/sig/checkpoint.h5 ]] || { kill -TERM "$pid"; echo "FAIL: no checkpoint appeared in 30 s"; exit 1; }
kill -TERM "$pid"
status=0; wait "$pid" || status=$?
cat "$work/sig.out"
[[ $status == 0 ]] || { echo "FAIL: SIGTERM gave exit status $status, expected 0"; exit 1; }
[[ $(field "$work/sig" stopped_by_signal) == SIGTERM ]] ||
  { echo "FAIL: report.json does not name SIGTERM: the signal did not stop the run"; exit 1; }
steps=$(field "$work/sig" steps)
((steps < 300)) || { echo "FAIL: SIGTERM landed after step $steps, past the reference's 300"; exit 1; }
grep -q "state after step $steps is in" "$work/sig.out" || { echo "FAIL: no message naming step $steps"; exit 1; }
[[ $(checkpoint_step "$drape" "$work/sig/checkpoint.h5") == "$steps" ]] ||
  { echo "FAIL: the checkpoint is not at the report's step $steps"; exit 1; }
# (No wall limit now: on busy cores the 30 s would cut the continuation short.)
OMP_NUM_THREADS=2 "$drape" --restart "$work/sig/checkpoint.h5" --set solver.steps=300 --set solver.wall_limit=0 \
  --quiet
[[ $(sum "$work/long-ref") == "$(sum "$work/sig")" ]] || { echo "FAIL: SIGTERM + restart differs"; exit 1; }
[[ $(field "$work/sig" steps) == "$(field "$work/long-ref" steps)" ]] || { echo "FAIL: restarted run ends at another step"; exit 1; }
echo "ok SIGTERM after step $steps, restarted: $(sum "$work/sig")"
