#!/usr/bin/env bash
# Failures lose no work: a rank killed with SIGKILL ends mpirun promptly with
# a non-zero status and leaves a checkpoint that restarts; a numerical failure
# (NaN injected on purpose) ends with exit 3 naming the step, and the last
# good checkpoint stays intact and restartable. No temporary file is left.
# An internal error on one rank alone (injected) ends both ranks at once,
# named by its rank, with the last checkpoint intact; a failure both ranks
# agree on (a checkpoint that cannot be renamed into place) ends them with
# exit 1, one message and no temporary file.
# Usage: failures_np2.sh DRAPE MPIEXEC SOURCE_DIR WORK_DIR
set -euo pipefail
drape=$1 mpiexec=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
scene=(--config "$src/run/scenes/small-box.toml" --set "cloth.particles=[25,25]" --set output.every=5
       --set output.picture=false --quiet)
no_tmp() { ! ls "$1"/*.tmp >/dev/null 2>&1 || { echo "FAIL: temporary files left in $1"; ls "$1"; exit 1; }; }

# kill -9 of one rank in a 2-rank run.
OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$drape" "${scene[@]}" --set solver.steps=100000 \
  --set output.checkpoint_every=2 --output "$work/kill" > "$work/kill.out" 2>&1 &
mpi=$!
for _ in $(seq 600); do [[ -e $work/kill/checkpoint.h5 ]] && break; sleep 0.05; done
[[ -e $work/kill/checkpoint.h5 ]] || { echo "FAIL: no checkpoint appeared"; exit 1; }
victim=$(pgrep -P "$mpi" | head -1)
[[ -n $victim ]] || { echo "FAIL: no rank process found under mpiexec $mpi"; exit 1; }
start=$SECONDS
kill -KILL "$victim"
status=0
for _ in $(seq 600); do kill -0 "$mpi" 2>/dev/null || break; sleep 0.1; done
if kill -0 "$mpi" 2>/dev/null; then
  kill -KILL "$mpi"; echo "FAIL: mpiexec still running 60 s after a rank was killed"; exit 1
fi
wait "$mpi" || status=$?
[[ $status != 0 ]] || { echo "FAIL: mpiexec exited 0 after a rank was killed"; exit 1; }
echo "ok mpiexec ended $((SECONDS - start)) s after kill -9, status $status"
step=$("$drape" --restart "$work/kill/checkpoint.h5" --dry-run | sed -n 's/.* at step \([0-9]*\)$/\1/p')
OMP_NUM_THREADS=1 "$drape" --restart "$work/kill/checkpoint.h5" --set solver.steps=$((step + 3)) \
  --output "$work/kill-continued" --quiet
[[ $(field "$work/kill-continued" steps) == $((step + 3)) ]] || { echo "FAIL: restart after kill -9"; exit 1; }
echo "ok the checkpoint of step $step restarts"

# NaN at step 12 with checkpoints every 5 steps.
status=0
DRAPE_FAULT_NAN_STEP=12 OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$drape" "${scene[@]}" --set solver.steps=40 \
  --set output.checkpoint_every=5 --output "$work/nan" > "$work/nan.out" 2>&1 || status=$?
cat "$work/nan.out"
[[ $status == 3 ]] || { echo "FAIL: exit status $status, expected 3"; exit 1; }
grep -q "drape: error: numerical failure at step 12, iteration" "$work/nan.out" ||
  { echo "FAIL: the message does not name step 12"; exit 1; }
[[ $(grep -c "drape: error:" "$work/nan.out") == 1 ]] || { echo "FAIL: not one message"; exit 1; }
[[ $(checkpoint_step "$drape" "$work/nan/checkpoint.h5") == 10 ]] ||
  { echo "FAIL: the last good checkpoint (step 10) is not intact"; exit 1; }
no_tmp "$work/nan"
OMP_NUM_THREADS=1 "$drape" --restart "$work/nan/checkpoint.h5" --set solver.steps=14 --output "$work/nan-continued" --quiet
echo "ok NaN at step 12: exit 3, checkpoint of step 10 intact and restartable"

# An internal error on rank 1 alone before step 12: rank 0 waits for it in the
# step's halo exchange, so only an abort ends the run.
status=0
DRAPE_FAULT_NAN_STEP=12 DRAPE_FAULT_INTERNAL_RANK=1 OMP_NUM_THREADS=1 timeout -k 10 60 "$mpiexec" -n 2 "$drape" \
  "${scene[@]}" --set solver.steps=40 --set output.checkpoint_every=5 --output "$work/internal" \
  > "$work/internal.out" 2>&1 || status=$?
cat "$work/internal.out"
[[ $status != 124 ]] || { echo "FAIL: rank 0 still waiting 60 s after rank 1's internal error"; exit 1; }
[[ $status != 0 ]] || { echo "FAIL: exit status 0 after an internal error"; exit 1; }
grep -q "drape: error: rank 1 of 2: internal: fault injected" "$work/internal.out" ||
  { echo "FAIL: the message does not name rank 1"; exit 1; }
[[ $(checkpoint_step "$drape" "$work/internal/checkpoint.h5") == 10 ]] ||
  { echo "FAIL: the last good checkpoint (step 10) is not intact"; exit 1; }
echo "ok internal error on rank 1: status $status, named, checkpoint of step 10 intact"

# On one rank the same error unwinds: exit 1, one message, no temporary file.
status=0
DRAPE_FAULT_NAN_STEP=12 DRAPE_FAULT_INTERNAL_RANK=0 OMP_NUM_THREADS=1 "$drape" "${scene[@]}" \
  --set solver.steps=40 --set output.checkpoint_every=5 --output "$work/internal1" > "$work/internal1.out" 2>&1 ||
  status=$?
[[ $status == 1 ]] || { echo "FAIL: one rank: exit status $status, expected 1"; exit 1; }
grep -qx "drape: error: internal: fault injected on purpose (DRAPE_FAULT_INTERNAL_RANK)" "$work/internal1.out" ||
  { cat "$work/internal1.out"; echo "FAIL: one rank: not the internal error's message"; exit 1; }
no_tmp "$work/internal1"
echo "ok internal error on one rank: exit 1, no temporary file"

# A failure the ranks agree on: rank 0 cannot rename the first checkpoint
# into place (a non-empty directory holds its name). Both unwind together.
mkdir -p "$work/agreed/checkpoint.h5" && touch "$work/agreed/checkpoint.h5/keep"
status=0
OMP_NUM_THREADS=1 timeout -k 10 60 "$mpiexec" -n 2 "$drape" "${scene[@]}" --set solver.steps=40 \
  --set output.checkpoint_every=5 --output "$work/agreed" > "$work/agreed.out" 2>&1 || status=$?
cat "$work/agreed.out"
[[ $status == 1 ]] || { echo "FAIL: agreed failure: exit status $status, expected 1"; exit 1; }
[[ $(grep -c "drape: error:" "$work/agreed.out") == 1 ]] || { echo "FAIL: agreed failure: not one message"; exit 1; }
grep -q "drape: error: checkpoint: cannot rename" "$work/agreed.out" ||
  { echo "FAIL: agreed failure: the message does not name the checkpoint"; exit 1; }
no_tmp "$work/agreed"
echo "ok a checkpoint that cannot be placed: exit 1, one message, no temporary file"
