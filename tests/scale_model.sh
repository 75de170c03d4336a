#!/usr/bin/env bash
# bench/scale_model on a tiny case (256 x 256, 4 and 16 parts, one rank: no ping-pong,
# a given latency and bandwidth): the invariants its figures must keep, whatever METIS chooses.
# Usage: scale_model.sh SCALE_MODEL WORK_DIR
set -euo pipefail
model=$1 work=$2
rm -rf "$work" && mkdir -p "$work"
# A bad flag is refused (exit 2) before any case runs.
for bad in "--parts 0" "--sizes ten" "--bogus 1"; do
  status=0
  timeout 60 "$model" $bad > "$work/refused.out" 2>&1 || status=$?
  [[ $status == 2 ]] || { echo "FAIL: scale_model $bad: exit $status, want 2"; cat "$work/refused.out"; exit 1; }
done
"$model" --sizes 256 --parts 4,16 --product-seconds 2e-7 --vector-seconds 2e-8 --alpha 1e-6 --beta 1e9 --json "$work/model.json" 2> "$work/stderr"
/usr/bin/python3 - "$work/model.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
cases = {c["parts"]: c for c in m["cases"]}
fail = []
def check(ok, what):
    if not ok:
        fail.append(what)
check(sorted(cases) == [4, 16], "cases for 4 and 16 parts")
check(m["work_from_tile_kinds_matches"], "tile work from the 3 x 3 kinds equals tile_work on the whole cloth")
for p, c in cases.items():
    tag = "%d parts: " % p
    check(c["tiles_in_parts"] == c["tiles"], tag + "every tile in one part")
    check(c["parts_without_tiles"] == 0, tag + "no part without a tile")
    check(abs(c["tiles_per_rank"]["mean"] * p - c["tiles"]) < 1e-9, tag + "mean tiles a rank = tiles / parts")
    check(abs(c["owned_particles"]["mean"] * p - c["particles"]) < 1e-6, tag + "owned particles add up to the cloth")
    check(c["imbalance"] >= 1, tag + "imbalance >= 1")
    check(c["edge_cut"] > 0, tag + "edge cut > 0")
    for k in ("ghost_particles", "sent_particles", "halo_bytes_cg_iteration", "halo_bytes_gradient", "neighbours"):
        check(c[k]["max"] >= c[k]["mean"] > 0, tag + k + ": max >= mean > 0")
    # Every particle sent is one ghost received somewhere.
    check(abs(c["sent_particles"]["mean"] - c["ghost_particles"]["mean"]) < 1e-9, tag + "sent = received in all")
    check(c["halo_bytes_cg_iteration"]["mean"] == 24 * c["sent_particles"]["mean"], tag + "24 bytes a particle a CG iteration")
    check(c["neighbours"]["max"] <= p - 1, tag + "neighbours <= parts - 1")
    # Ghosts lie within 2 of the owned tiles: at most each tile's ring, 8t + 16.
    check(c["ghost_particles"]["max"] <= c["tiles_per_rank"]["max"] * (8 * m["tile"] + 16), tag + "ghosts within the tiles' rings")
    f = c["fold_band_migration"]
    check(f["imbalance_before"] > f["imbalance_after"] >= 1 or f["tiles_moved"] == 0, tag + "rebalance lowers the imbalance")
    check(f["imbalance_before"] > m["imbalance_threshold"], tag + "the fold band unbalances the coarse parts")
    check(0 < f["bytes"] <= f["tiles_moved"] * m["tile"] ** 2 * 128, tag + "tiles moved, at most 128 bytes a particle")
    check(f["bytes"] >= f["bytes_max_rank"] > 0, tag + "bytes over all ranks >= one rank's")
    check(c["iteration_seconds_modelled"] > 0, tag + "iteration time")
# More parts: each rank holds less and sends less, the cut grows.
check(cases[16]["halo_bytes_cg_iteration"]["mean"] < cases[4]["halo_bytes_cg_iteration"]["mean"], "mean halo bytes fall with parts")
check(cases[16]["owned_particles"]["max"] < cases[4]["owned_particles"]["max"], "owned particles fall with parts")
check(cases[16]["edge_cut"] > cases[4]["edge_cut"], "edge cut grows with parts")
check(cases[16]["iteration_seconds_modelled"] < cases[4]["iteration_seconds_modelled"], "16 ranks faster than 4 on 256^2")
if fail:
    print("FAIL:\n  " + "\n  ".join(fail))
    sys.exit(1)
print("scale_model: invariants hold for %s parts" % sorted(cases))
PY
