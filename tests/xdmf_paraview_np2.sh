#!/usr/bin/env bash
# drape.xdmf opened by ParaView (pvbatch, headless), for a 1-rank and a
# 2-rank run: see xdmf_paraview.py for what is checked.
# Usage: xdmf_paraview_np2.sh DRAPE MPIEXEC SOURCE_DIR WORK_DIR PVBATCH
set -euo pipefail
drape=$1 mpiexec=$2 src=$3 work=$4 pvbatch=$5
rm -rf "$work" && mkdir -p "$work"
scene=(--config "$src/run/scenes/small-box.toml" --set "cloth.particles=[17,17]" --set solver.steps=6
       --set output.every=2 --set output.picture=false --quiet)
OMP_NUM_THREADS=1 "$drape" "${scene[@]}" --output "$work/np1"
OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$drape" "${scene[@]}" --output "$work/np2"
for run in np1 np2; do
  # ParaView's Python is the system's, where h5py is; keep a virtual
  # environment's or a user's site out of it.
  env -u PYTHONPATH -u PYTHONHOME "$pvbatch" "$src/tests/xdmf_paraview.py" "$work/$run"
done
