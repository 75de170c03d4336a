#!/usr/bin/env bash
# A 2-rank run killed (SIGKILL) inside a checkpoint write leaves on disk
# either the previous checkpoint or the new one, whole: never a mix, never a
# damaged file. The write is paused at each of its points in turn (the test
# hook DRAPE_TEST_STALL_CHECKPOINT: before the data, halfway through it,
# before the rename, after it) and the ranks are killed there (both, or one
# of them, drawn at random; mpiexec ends the other). What is left restarts,
# and the continued run ends with the uninterrupted run's state checksum.
# Usage: kill_checkpoint_np2.sh DRAPE MPIEXEC SOURCE_DIR WORK_DIR
set -euo pipefail
drape=$1 mpiexec=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
scene=(--config "$src/run/scenes/small-box.toml" --set "cloth.particles=[17,17]" --set output.every=0
       --set output.picture=false --quiet)
steps=20
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
at_step() { "$drape" --restart "$1/checkpoint.h5" --dry-run | sed -n 's/.* at step \([0-9]*\)$/\1/p'; }
seed=${DRAPE_TEST_SEED:-$RANDOM}
RANDOM=$seed
echo "victims drawn with DRAPE_TEST_SEED=$seed"

OMP_NUM_THREADS=1 "$drape" "${scene[@]}" --set solver.steps=$steps --output "$work/ref"
for point in before-data mid-data before-rename after-rename; do
  dir=$work/$point
  # The previous checkpoint: step 4. The new one would be step 8.
  OMP_NUM_THREADS=1 "$drape" "${scene[@]}" --set solver.steps=4 --set output.checkpoint_every=4 --output "$dir"
  DRAPE_TEST_STALL_CHECKPOINT=$point:60 OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$drape" --restart "$dir/checkpoint.h5" \
    --set solver.steps=$steps --set output.checkpoint_every=4 --quiet > "$work/$point.out" 2>&1 &
  mpi=$!
  for _ in $(seq 600); do grep -q "stalled at $point" "$work/$point.out" && break; sleep 0.1; done
  grep -q "stalled at $point" "$work/$point.out" || { kill -KILL "$mpi"; cat "$work/$point.out"; echo "FAIL $point: never reached"; exit 1; }
  ranks=($(pgrep -P "$mpi"))
  ((${#ranks[@]} == 2)) || { kill -KILL "$mpi"; echo "FAIL $point: ${#ranks[@]} rank processes under mpiexec"; exit 1; }
  case $((RANDOM % 3)) in
    0) victims=("${ranks[@]}") who="both rank processes" ;;
    1) victims=("${ranks[0]}") who="the first rank process" ;;
    2) victims=("${ranks[1]}") who="the second rank process" ;;
  esac
  kill -KILL "${victims[@]}"
  status=0
  timeout 60 tail --pid="$mpi" -f /dev/null || { kill -KILL "$mpi"; echo "FAIL $point: mpiexec still running"; exit 1; }
  wait "$mpi" || status=$?
  [[ $status != 0 ]] || { echo "FAIL $point: mpiexec exited 0 after kill -9"; exit 1; }
  expected=4
  [[ $point != after-rename ]] || expected=8
  step=$(at_step "$dir") || { echo "FAIL $point: the checkpoint left does not read"; exit 1; }
  [[ $step == "$expected" ]] || { echo "FAIL $point: the checkpoint is at step '$step', expected $expected"; exit 1; }
  OMP_NUM_THREADS=1 "$drape" --restart "$dir/checkpoint.h5" --set solver.steps=$steps --quiet
  [[ $(sum "$work/ref") == "$(sum "$dir")" ]] ||
    { echo "FAIL $point: the restart ends at $(sum "$dir"), not at $(sum "$work/ref")"; exit 1; }
  echo "ok killed $who at $point: the checkpoint of step $step restarts to $(sum "$dir")"
done
