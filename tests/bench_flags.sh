#!/usr/bin/env bash
# The measuring programs refuse a flag they do not know, or a value out of
# range, with one message naming it and exit 2, instead of running a long
# benchmark with their defaults.
# Usage: bench_flags.sh SCALING RANKS_THREADS MPIEXEC WORK_DIR
set -uo pipefail
scaling=$1 ranks_threads=$2 mpiexec=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
refused() {  # refused NAME WANT COMMAND...: exit 2 and exactly one line naming WANT
  local name=$1 want=$2; shift 2
  timeout 60 "$@" > "$work/$name.out" 2>&1
  local status=$?
  [[ $status == 2 ]] || { echo "FAIL: $name: exit $status, want 2"; cat "$work/$name.out"; exit 1; }
  local n; n=$(grep -c -- "$want" "$work/$name.out")
  [[ $n == 1 ]] || { echo "FAIL: $name: $n lines name $want, want 1"; cat "$work/$name.out"; exit 1; }
}
refused unknown "--bogus" "$scaling" --bogus 1
refused range "--iterations" "$scaling" --iterations 0
refused not_a_number "--size" "$scaling" --size ten
# mpiexec reports a rank's exit status as its own; every rank leaves, one speaks.
timeout 60 "$mpiexec" -n 2 "$ranks_threads" --size 2 > "$work/mpi.out" 2>&1
status=$?
[[ $status != 0 && $status != 124 ]] || { echo "FAIL: ranks_threads: exit $status"; cat "$work/mpi.out"; exit 1; }
n=$(grep -c -- "--size: " "$work/mpi.out")
[[ $n == 1 ]] || { echo "FAIL: ranks_threads: $n messages, want 1"; cat "$work/mpi.out"; exit 1; }
echo "bench_flags: all refused"
