#!/usr/bin/env bash
# bench/hypre_compare at a tiny size: it exits 0, prints a converged row for
# drape's multigrid and for BoomerAMG's defaults, and writes its JSON.
# Usage: hypre_compare.sh HYPRE_COMPARE WORK_DIR
set -uo pipefail
program=$1 work=$2
rm -rf "$work" && mkdir -p "$work"
timeout 100 "$program" --size 17 --time 0.01 --json "$work/out.json" > "$work/out.txt" 2>&1
status=$?
[[ $status == 0 ]] || { echo "FAIL: exit $status, want 0"; cat "$work/out.txt"; exit 1; }
for row in "multigrid " "boomeramg-default "; do
  line=$(grep -- "^$row" "$work/out.txt")
  [[ -n $line ]] || { echo "FAIL: no row for $row"; cat "$work/out.txt"; exit 1; }
  [[ $line != *"NOT CONVERGED"* ]] || { echo "FAIL: $row did not converge"; cat "$work/out.txt"; exit 1; }
done
grep -q '"boomeramg-default"' "$work/out.json" || { echo "FAIL: no JSON"; exit 1; }
echo "hypre_compare: both methods ran"
