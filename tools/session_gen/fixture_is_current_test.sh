#!/bin/sh
# A golden session is what its generator writes today:
#   fixture_is_current_test.sh GENERATOR OUT.jsonl FIXTURE.jsonl [GENERATOR ARGS...]
# runs GENERATOR ARGS... OUT.jsonl and compares OUT.jsonl with FIXTURE.jsonl
# byte for byte (tools/session_gen/CMakeLists.txt).
set -u
gen=$1
out=$2
fixture=$3
shift 3
rm -f "$out"
"$gen" "$@" "$out" || { echo "FAIL: $gen exited $?" >&2; exit 1; }
cmp "$out" "$fixture" || {
  echo "FAIL: $fixture is not what $gen writes today: regenerate it" >&2
  exit 1
}
