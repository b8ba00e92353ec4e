#!/bin/sh
# `mocosim plot` from the command line: each test is one case, run as
#   plot_cli_test.sh TEST MOCOSIM WORKDIR SOURCE_DIR
# and registered with CTest under its own name (emulator/plot/CMakeLists.txt).
set -u
test_name=$1
sim=$2
work=$3/$test_name
src=$4
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 1
# shellcheck source=../../tools/cli_test_lib.sh
. "$src/tools/cli_test_lib.sh"
sessions=$src/fixtures/sessions
profiles=$src/fixtures/profiles

case "$test_name" in

# Exit 0 with an SVG written (no partial file left) and the peak deviation
# reported.
mocosim_plot_fixture)
  expect_rc 0 "$sim" plot "$sessions/dmc16-boom-move.jsonl" --profile "$profiles/dmc16-boom.json" \
    -o boom.svg
  head -c 5 boom.svg | grep -q '^<svg\|^<?xml' || fail "boom.svg is not an SVG"
  grep -q 'peak deviation' out.txt || fail "no peak deviation on stdout"
  ls | grep -q partial && fail "a partial file is left"
  ;;

# Exit 2, and a message naming the problem, for a profile without
# physical_rig, an unreadable profile and a non-DMC session; no SVG written.
mocosim_plot_bad_profile)
  expect_rc 2 "$sim" plot "$sessions/dmc16-boom-move.jsonl" --profile "$profiles/dmc16.json" \
    -o no.svg
  grep -q physical_rig err.txt || fail "does not name physical_rig"
  expect_rc 2 "$sim" plot "$sessions/dmc16-boom-move.jsonl" --profile /nonexistent.json -o no.svg
  expect_rc 2 "$sim" plot "$sessions/dfmoco-uno-workflow.jsonl" --profile "$profiles/dmc16-boom.json" \
    -o no.svg
  test ! -e no.svg || fail "no.svg was written"
  ;;

*)
  echo "unknown test $test_name" >&2
  exit 1
  ;;
esac
cleanup
exit 0
