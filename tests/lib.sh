# Shared by the test scripts (source it): reading a run's report.json with
# Python's json, never by pattern.
#   report DIR EXPR   EXPR on r = DIR/report.json (strings as they are, the
#                     rest as JSON: true, 0.25, [1, 2])
#   field DIR KEY     a top-level entry
#   sum DIR           the run's state checksum; without one "missing:DIR",
#                     so that two runs without a checksum never agree
#   checkpoint_step DRAPE FILE   the step a checkpoint holds, from --dry-run's
#                     first line (read whole: a reader that stops early would
#                     end the program by SIGPIPE once its output passes a
#                     pipe's buffer)
report() {
  python3 - "$1/report.json" "$2" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
v = eval(sys.argv[2], {"r": r})
print(v if isinstance(v, str) else json.dumps(v))
PY
}
field() { report "$1" "r[\"$2\"]"; }
sum() {
  local s
  s=$(field "$1" state_checksum 2>/dev/null) || true
  [[ $s =~ ^[0-9a-f]{32}$ ]] && echo "$s" || echo "missing:$1"
}
checkpoint_step() {
  local out
  out=$("$1" --restart "$2" --dry-run) || return 1
  out=${out%%$'\n'*}
  [[ $out =~ " at step "([0-9]+)$ ]] && echo "${BASH_REMATCH[1]}"
}
