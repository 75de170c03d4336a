#!/usr/bin/env bash
# Restart inside grid sequencing's easing window: the split to the finer
# mesh lengthens the rest lengths of the edges it left stretched, and they
# relax back over the next steps (amrc/sequence.hpp). A run stopped a few
# steps after the split, on 2 ranks, and continued on 1 rank x 2 threads
# or on 3 ranks ends in the uninterrupted run's state, bit for bit: its
# checkpoint holds the eased rest lengths (/state/eased_rest), not only the
# material's.
# Usage: restart_eased_np3.sh DRAPE MPIEXEC SOURCE_DIR WORK_DIR
set -euo pipefail
drape=$1 mpiexec=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
fail() { echo "FAIL: $*"; exit 1; }
# 33 x 33 sequenced from the level-2 mesh (9 x 9) to level 1 (17 x 17). A
# thin contact layer on every mesh (not the coarse mesh's own thick one):
# the coarse chords over the box's edges cut into it, and the split's new
# particles there are lifted out, their edges stretched tens of per cent.
scene=(--config "$src/run/scenes/small-box.toml" --set "cloth.particles=[33,33]" --set cloth.tile=8
       --set amrc.start_spacing=0.13 --set solver.contact_thickness=0.01 --set solver.wall_limit=0
       --set output.picture=false --set output.every=0)

# The step of the split: level 2's rest.
OMP_NUM_THREADS=1 "$drape" "${scene[@]}" --set amrc.last_level=2 --set solver.steps=100000 --quiet \
  --output "$work/probe"
[[ $(field "$work/probe" at_rest) == true ]] || fail "level 2 did not come to rest"
split=$(field "$work/probe" steps)
before=$((split - 2)) cut=$((split + 3)) end=$((split + 12))

# The reference: uninterrupted to `end`, 1 rank x 1 thread.
OMP_NUM_THREADS=1 "$drape" "${scene[@]}" --set amrc.last_level=1 --set solver.steps=$end --quiet --output "$work/ref"
[[ $(report "$work/ref" 'r["stages"][1]["from_step"]') == "$split" ]] || fail "the reference split elsewhere"
# 1 rank ends 2 steps before the split; 2 ranks go on from there (only
# the last steps, to keep the test short), split, end 3 steps
# later inside the window and write the checkpoint together; 1 rank x 2
# threads go on from it.
OMP_NUM_THREADS=1 "$drape" "${scene[@]}" --set amrc.last_level=1 --set solver.steps=$before \
  --set output.checkpoint_every=$before --quiet --output "$work/part"
OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$drape" --restart "$work/part/checkpoint.h5" --set solver.steps=$cut \
  --set output.checkpoint_every=$cut > "$work/part.out" 2>&1 || { cat "$work/part.out"; fail "the 2-rank part"; }
eased=$(sed -n 's/.*edges eased from up to \([0-9.]*\) % strain.*/\1/p' "$work/part.out")
python3 -c "import sys; sys.exit(not float('${eased:-0}') > 1)" ||
  fail "the split eased no edge beyond 1 % (got '$eased' %): nothing to restart inside"
h5ls "$work/part/checkpoint.h5/state" | grep -q '^eased_rest ' ||
  fail "the checkpoint at step $cut (split at $split) holds no eased rest lengths"
cp -r "$work/part" "$work/part3"
"$drape" --restart "$work/part/checkpoint.h5" --set solver.steps=$end --threads 2 --quiet
[[ $(field "$work/part" steps) == "$end" ]] || fail "the restarted run did not reach step $end"
[[ $(sum "$work/part") == "$(sum "$work/ref")" ]] ||
  fail "restarted at step $cut (split at $split, eased $eased %): $(sum "$work/part") vs $(sum "$work/ref")"
echo "ok split at step $split easing up to $eased %, restarted at $cut on 1 rank of 2: $(sum "$work/ref")"
# 3 ranks go on from the same checkpoint: each reads its own particles' and
# ghosts' eased lengths only.
OMP_NUM_THREADS=1 "$mpiexec" -n 3 "$drape" --restart "$work/part3/checkpoint.h5" --set solver.steps=$end --quiet
[[ $(sum "$work/part3") == "$(sum "$work/ref")" ]] ||
  fail "restarted at step $cut on 3 ranks: $(sum "$work/part3") vs $(sum "$work/ref")"
echo "ok restarted at $cut on 3 ranks of 2: $(sum "$work/ref")"
