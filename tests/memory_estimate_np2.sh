#!/usr/bin/env bash
# The memory estimate that refuses a cloth too large for its ranks
# (src/app/memory.cpp; report.json's estimated_peak_bytes_per_rank) against
# the peak it estimates (peak_rss_bytes, the largest rank's), on the finest
# mesh in free fall (before any multigrid, which it leaves out): never below
# it, on 1 and 2 ranks and with AMRC; and its bytes a particle, the growth
# from 200 x 200 to 400 x 400, within 1.5 times the measured growth (an
# estimate far above the peak refuses cloths that fit).
# Usage: memory_estimate_np2.sh DRAPE MPIEXEC SOURCE_DIR WORK_DIR
set -euo pipefail
drape=$1 mpiexec=$2 work=$4
rm -rf "$work" && mkdir -p "$work"
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
run=(--quiet --set solver.steps=2 --set amrc.start_spacing=0 --set output.every=0 --set output.picture=false
     --set solver.wall_limit=0)
check() {  # DIR: the estimate bounds the peak
  local peak est
  peak=$(field "$1" peak_rss_bytes) est=$(field "$1" estimated_peak_bytes_per_rank)
  (( peak <= est )) || { echo "FAIL: $1: peak $peak bytes above the estimate $est"; exit 1; }
  echo "ok $(basename "$1"): peak $((peak >> 20)) MiB, estimate $((est >> 20)) MiB"
}
for n in 200 400; do
  OMP_NUM_THREADS=1 "$drape" "${run[@]}" --set "cloth.particles=[$n,$n]" --output "$work/one-$n"
  check "$work/one-$n"
done
python3 - "$work/one-200/report.json" "$work/one-400/report.json" <<'PY'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
n = 400 * 400 - 200 * 200
peak = (b["peak_rss_bytes"] - a["peak_rss_bytes"]) / n
est = (b["estimated_peak_bytes_per_rank"] - a["estimated_peak_bytes_per_rank"]) / n
assert peak <= est <= 1.5 * peak, f"FAIL: the estimate grows {est:.0f} bytes a particle, the peak {peak:.0f}"
print(f"ok bytes a particle: estimated {est:.0f}, measured {peak:.0f}")
PY
OMP_NUM_THREADS=1 "$drape" "${run[@]}" --set "cloth.particles=[400,400]" --set amrc.enabled=true --output "$work/amrc"
check "$work/amrc"
OMP_NUM_THREADS=1 "$mpiexec" -n 2 "$drape" "${run[@]}" --set "cloth.particles=[400,400]" --output "$work/two"
check "$work/two"
OMP_NUM_THREADS=1 "$drape" "${run[@]}" --set "cloth.particles=[400,400]" --set solver.method=cg --output "$work/cg"
check "$work/cg"
