#!/usr/bin/env bash
# A write that fails ends the run cleanly: under a file-size limit (ulimit -f;
# a full disk takes the same path: the writers claim the room a frame or a
# checkpoint needs first) a frame or a checkpoint that does not fit ends the run with exit 1
# and one message naming the file, leaves no temporary file, and keeps the
# previous checkpoint, which restarts to the uninterrupted run's state. On
# 1 rank and on 2 (parallel HDF5's collective write). SIGXFSZ, which would
# kill the run silently, is ignored by drape so that the write fails instead.
# Where a 160 KiB tmpfs can be mounted (root), a really full disk on 2 ranks.
# Usage: disk_full.sh DRAPE MPIEXEC SOURCE_DIR WORK_DIR
set -euo pipefail
drape=$1 mpiexec=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
scene=(--config "$src/run/scenes/small-box.toml" --set "cloth.particles=[17,17]" --set output.picture=false
       --quiet)
steps=24
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
no_tmp() { ! ls "$1"/*.tmp >/dev/null 2>&1 || { echo "FAIL $2: temporary files left in $1"; ls "$1"; exit 1; }; }
at_step() { "$drape" --restart "$1/checkpoint.h5" --dry-run | sed -n 's/.* at step \([0-9]*\)$/\1/p'; }
# Open MPI's shared memory (PMIx's store, the ranks' own) lives in files that
# the limit would refuse: under a limit they use a hash table and TCP.
launch() {  # launch RANKS ARGS...: drape on RANKS ranks
  local n=$1; shift
  export PMIX_MCA_gds=hash OMPI_MCA_btl=self,tcp
  if ((n == 1)); then "$drape" "$@"; else "$mpiexec" -n "$n" "$drape" "$@"; fi
}
limited() {  # limited KB LABEL RANKS ARGS...: a run under ulimit -f KB, which must fail
  local kb=$1 label=$2; shift 2
  local status=0
  (ulimit -f "$kb" && OMP_NUM_THREADS=1 launch "$@") > "$work/$label.out" 2>&1 || status=$?
  cat "$work/$label.out"
  [[ $status == 1 ]] || { echo "FAIL $label: exit status $status, expected 1"; exit 1; }
  [[ $(grep -c "drape: error:" "$work/$label.out") == 1 ]] || { echo "FAIL $label: not one message"; exit 1; }
}
# restarted DIR LABEL: the checkpoint in DIR continues to the reference's state.
restarted() {
  OMP_NUM_THREADS=1 "$drape" --restart "$1/checkpoint.h5" --set solver.steps=$steps --output "$work/$2-continued"
  [[ $(sum "$work/ref") == "$(sum "$work/$2-continued")" ]] ||
    { echo "FAIL $2: the restart ends at $(sum "$work/$2-continued"), not at $(sum "$work/ref")"; exit 1; }
}

OMP_NUM_THREADS=1 "$drape" "${scene[@]}" --set solver.steps=$steps --output "$work/ref"
# Sizes: a checkpoint, and a frames file holding one frame (output.every=0).
OMP_NUM_THREADS=1 "$drape" "${scene[@]}" --set solver.steps=2 --set output.checkpoint_every=2 \
  --set output.every=0 --output "$work/sizes"
checkpoint_kb=$(( $(stat -c %s "$work/sizes/checkpoint.h5") / 1024 ))
echo "checkpoint: $checkpoint_kb KiB, one frame's file: $(( $(stat -c %s "$work/sizes/drape.h5") / 1024 )) KiB"

for ranks in 1 2; do
  # A frame that does not fit: a frame every step, a checkpoint every step,
  # a limit of 2.5 checkpoints that the frames file soon outgrows.
  dir=$work/frame-np$ranks
  limited $((checkpoint_kb * 5 / 2)) frame-np$ranks $ranks "${scene[@]}" --set solver.steps=$steps \
    --set output.every=1 --set output.checkpoint_every=1 --output "$dir"
  grep -q "drape: error: cannot write $dir/drape.h5.tmp: " "$work/frame-np$ranks.out" ||
    { echo "FAIL frame-np$ranks: the message does not name drape.h5.tmp"; exit 1; }
  no_tmp "$dir" frame-np$ranks
  step=$(at_step "$dir")
  ((step > 0 && step < steps)) || { echo "FAIL frame-np$ranks: the checkpoint is at step '$step'"; exit 1; }
  restarted "$dir" frame-np$ranks
  echo "ok $ranks rank(s): a frame too large: exit 1, named, no temporary, the checkpoint of step $step restarts"

  # A checkpoint that does not fit, after one that did: the run is continued
  # from step 4 without its frames file (so that only the checkpoint meets the
  # limit, three quarters of its size) and must keep the checkpoint of step 4.
  dir=$work/checkpoint-np$ranks
  OMP_NUM_THREADS=1 "$drape" "${scene[@]}" --set solver.steps=4 --set output.checkpoint_every=4 \
    --set output.every=0 --output "$dir"
  rm "$dir/drape.h5"
  limited $((checkpoint_kb * 3 / 4)) checkpoint-np$ranks $ranks --restart "$dir/checkpoint.h5" \
    --set solver.steps=$steps --set output.checkpoint_every=2 --quiet
  grep -q "drape: error: checkpoint: cannot write $dir/checkpoint.h5.tmp: " "$work/checkpoint-np$ranks.out" ||
    { echo "FAIL checkpoint-np$ranks: the message does not name checkpoint.h5.tmp"; exit 1; }
  no_tmp "$dir" checkpoint-np$ranks
  [[ $(at_step "$dir") == 4 ]] || { echo "FAIL checkpoint-np$ranks: the checkpoint of step 4 is gone"; exit 1; }
  restarted "$dir" checkpoint-np$ranks
  echo "ok $ranks rank(s): a checkpoint too large: exit 1, named, no temporary, the checkpoint of step 4 restarts"
done

# A full disk, where one can be made (root may mount a 160 KiB tmpfs): 2 ranks,
# a frame and a checkpoint every step, until one of them no longer fits.
full=$work/full
mkdir -p "$full"
if mount -t tmpfs -o size=160k tmpfs "$full" 2>/dev/null; then
  trap 'umount "$full"' EXIT
  status=0
  OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$drape" "${scene[@]}" --set solver.steps=$steps --set output.every=1 \
    --set output.checkpoint_every=1 --output "$full/run" > "$work/full.out" 2>&1 || status=$?
  cat "$work/full.out"
  [[ $status == 1 ]] || { echo "FAIL full disk: exit status $status, expected 1"; exit 1; }
  # Which file meets the full disk first (the frames or a checkpoint's
  # second copy) depends on their sizes by a few hundred bytes: either is named.
  grep -Eq "drape: error: (checkpoint: )?cannot write $full/run/(drape|checkpoint)\.h5\.tmp: .*No space left on device" "$work/full.out" ||
    { echo "FAIL full disk: the message does not name the file and the full disk"; exit 1; }
  no_tmp "$full/run" "full disk"
  step=$(at_step "$full/run")
  ((step > 0)) || { echo "FAIL full disk: no checkpoint kept"; exit 1; }
  restarted "$full/run" full
  echo "ok 2 ranks: a full disk: exit 1, named, no temporary, the checkpoint of step $step restarts"
else
  echo "(no full-disk case: a tmpfs cannot be mounted here)"
fi
