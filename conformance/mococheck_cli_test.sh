#!/bin/sh
# mococheck's command line against hostile input and hostile targets (issue
# 13): each test is one function, run as
#   mococheck_cli_test.sh TEST MOCOCHECK MOCOSIM WORKDIR SOURCE_DIR
# and registered with CTest under its own name (conformance/CMakeLists.txt).
# Waits are bounded polls for an event (a log line, a file), never timings.
set -u
test_name=$1
m=$2
sim=$3
work=$4/$test_name
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 1
# shellcheck source=../tools/cli_test_lib.sh
. "$5/tools/cli_test_lib.sh"

# Starts `mocosim dmc16 --tcp 127.0.0.1:0` logging to sim.log; sets sim_pid, port.
start_device() {
  "$sim" dmc16 --tcp 127.0.0.1:0 --no-pacing "$@" >sim.log 2>&1 &
  sim_pid=$!
  pids="$pids $sim_pid"
  wait_for grep -q ' on tcp 127.0.0.1:' sim.log || fail "mocosim did not start"
  port=$(sed -n 's/.* on tcp 127\.0\.0\.1:\([0-9]*\).*/\1/p' sim.log | head -1)
  [ -n "$port" ] || fail "no port in the log"
}

case "$test_name" in

# The device closes a second client at once: a target error (2) with every
# report written, not a SIGPIPE death (141) or a FAIL (1).
mococheck_cli_tcp_target_that_hangs_up_is_a_target_error_with_reports)
  start_device
  "$m" run --target "tcp:127.0.0.1:$port" -q >first.txt 2>&1 &
  first=$!
  pids="$pids $first"
  wait_for grep -q 'host connected' sim.log || fail "the first client did not connect"
  expect_rc 2 "$m" run --target "tcp:127.0.0.1:$port" --junit r.xml --json r.json --html r.html
  grep -q 'target error' err.txt || fail "stderr does not say target error"
  grep -q '^result: TARGET ERROR' out.txt || fail "no TARGET ERROR verdict on the console"
  test -s r.xml && test -s r.json && test -s r.html || fail "reports missing"
  grep -q '"exit_code": 2' r.json || fail "JSON exit_code is not 2"
  grep -q '<error message="target error' r.xml || fail "JUnit has no error"
  kill -9 "$first"
  ;;

# The device dies in the middle of the run: a target error with reports.
mococheck_cli_device_dying_mid_run_is_a_target_error_with_reports)
  start_device
  "$m" run --target "tcp:127.0.0.1:$port" --json r.json >out.txt 2>err.txt &
  check=$!
  pids="$pids $check"
  wait_for grep -q '^  ok  ' out.txt || fail "no case finished"
  kill -9 "$sim_pid"
  wait "$check"
  rc=$?
  [ "$rc" = 2 ] || fail "exit $rc, not 2"
  grep -q '"target_error": "the device closed the connection"' r.json || fail "no target_error"
  ;;

# SIGHUP (and SIGTERM) stop the run after the current case; the reports of
# what ran are written and the run has no verdict (2).
mococheck_cli_sighup_and_sigterm_write_reports_and_exit_2)
  start_device
  for sig in HUP TERM; do
    rm -f r.json r.xml out.txt
    "$m" run --target "tcp:127.0.0.1:$port" --json r.json --junit r.xml >out-$sig.txt 2>err.txt &
    check=$!
    pids="$pids $check"
    wait_for grep -q '^  ok  ' out-$sig.txt || fail "no case finished"
    kill -$sig "$check"
    wait "$check"
    rc=$?
    [ "$rc" = 2 ] || fail "SIG$sig: exit $rc, not 2"
    grep -q '^result: INTERRUPTED' out-$sig.txt || fail "SIG$sig: no INTERRUPTED verdict"
    grep -q '"interrupted_by_signal": [1-9]' r.json || fail "SIG$sig: JSON not marked"
    test -s r.xml || fail "SIG$sig: no JUnit report"
  done
  ;;

# Each case's verdict reaches a file (not a terminal) as the case ends: the
# first one is there while the run still goes on.
mococheck_cli_streams_each_case_verdict_as_it_ends)
  start_device
  "$m" run --target "tcp:127.0.0.1:$port" >out.txt 2>err.txt &
  check=$!
  pids="$pids $check"
  wait_for grep -q '^  ok  ' out.txt || fail "no case verdict before the end of the run"
  grep -q '^mococheck: tcp:127.0.0.1:' out.txt || fail "no title line"
  grep -q '^device: ' out.txt || fail "no device line"
  kill -0 "$check" || fail "the run had ended: nothing proved"
  kill -9 "$check"
  ;;

# A regular file given as serial:/pty: is refused (2) and left as it was.
mococheck_cli_serial_target_that_is_a_regular_file_is_never_written)
  printf 'precious\n' >file.dat
  cp file.dat before.dat
  for kind in serial pty; do
    expect_rc 2 "$m" run --target "$kind:file.dat"
    grep -q "$kind:file.dat is a regular file" err.txt || fail "$kind: message"
    cmp file.dat before.dat || fail "$kind: the file was written"
  done
  expect_rc 2 "$m" run --target serial:.
  grep -q 'is a directory' err.txt || fail "directory message"
  expect_rc 2 "$m" replay "$5/fixtures/sessions/dmc16-workflow.jsonl" --target serial:file.dat
  cmp file.dat before.dat || fail "replay wrote the file"
  ;;

# Numbers: not a finite number in range is a usage error naming the option.
mococheck_cli_numbers_not_finite_or_out_of_range_are_usage_errors)
  s=$5/fixtures/sessions/dmc16-workflow.jsonl
  for args in "fuzz $s --seconds nan" "fuzz $s --seconds inf" "fuzz $s --seconds -1" \
              "fuzz $s --runs 18446744073709551615" "fuzz $s --runs -1" \
              "fuzz $s --seed -1" "fuzz $s --seed 18446744073709551616" "fuzz $s --seed 1e23" \
              "fuzz $s --max-failures 0" "fuzz $s --max-failures 1.5" \
              "run --target in-process:dmc16 --seed -1" "run --target in-process:dmc16 --steps 1e3" \
              "run --target in-process:dmc16 --deadline-ms nan" \
              "run --target in-process:dmc16 --answer-timeout-ms 0x10" \
              "run --target in-process:dmc16 --position-gap-ms 99999999999999999999" \
              "run --target in-process:dmc16 --baud -115200" \
              "run --target in-process:dmc16 --deadline rt=1e3" \
              "run --target in-process:dmc16 --shard 1x/2" \
              "replay $s --position-tolerance -1" "replay $s --time-tolerance-ms nan" \
              "replay $s --baud 1e9"; do
    opt=$(echo "$args" | sed 's/.* \(--[a-z-]*\) [^ ]*$/\1/')
    # shellcheck disable=SC2086
    expect_rc 2 "$m" $args
    grep -q -- "$opt" err.txt || fail "the message does not name $opt: $args"
    grep -q 'result:' out.txt && fail "ran anyway: $args"
  done
  # The edges of the ranges are accepted.
  expect_rc 0 "$m" fuzz "$s" --seed 18446744073709551615 --runs 1 --crashes crashes
  expect_rc 0 "$m" run --target in-process:dmc16 --seed 0 --steps 1 -q --cases 'random/*'
  ;;

# A --cases filter that selects nothing is a usage error, like --rules.
mococheck_cli_cases_filter_selecting_nothing_is_a_usage_error)
  expect_rc 2 "$m" run --target in-process:dmc16 --cases 'nope/*'
  grep -q "mococheck cases" err.txt || fail "no pointer to 'mococheck cases'"
  grep -q 'result:' out.txt && fail "ran anyway"
  expect_rc 2 "$m" run --target in-process:stackshot3x --cases 'motor/*'
  grep -q -- "--protocol stackshot" err.txt || fail "no protocol in the hint"
  expect_rc 0 "$m" run --target in-process:dmc16 --cases 'connect/*' -q
  ;;

# Report paths are checked before the run; two reports on one path are refused.
mococheck_cli_report_paths_are_checked_before_the_run)
  mkdir adir
  for args in "--junit no/such/dir/r.xml" "--json adir" "--html adir/" \
              "--junit r.xml --json r.xml" "--json r.json --html ./r.json" \
              "--junit adir/../r.xml --html r.xml"; do
    # shellcheck disable=SC2086
    expect_rc 2 "$m" run --target in-process:dmc16 $args
    grep -q 'result:' out.txt && fail "ran before refusing: $args"
    grep -q -- '--' err.txt || fail "the message names no option: $args"
  done
  test ! -e r.xml && test ! -e r.json || fail "a report was written"
  # An empty report path (an unset shell variable) is refused, not ignored.
  for opt in --junit --json --html --save-session; do
    expect_rc 2 "$m" run --target in-process:dmc16 $opt ""
    grep -q -- "$opt: needs a path" err.txt || fail "empty $opt accepted"
  done
  if [ "$(id -u)" != 0 ]; then
    mkdir ro && chmod 555 ro
    expect_rc 2 "$m" run --target in-process:dmc16 --json ro/r.json
    grep -q 'not writable' err.txt || fail "read-only directory message"
  fi
  expect_rc 0 "$m" run --target in-process:dmc16 -q --junit r.xml --json r.json --html r.html
  ;;

# Parse errors of every kind are 2 (CLI11's own codes, e.g. 105, never leak);
# --help is 0.
mococheck_cli_parse_errors_exit_2_and_help_exits_0)
  mkdir adir
  expect_rc 2 "$m" run --target in-process:dmc16 --profile adir
  expect_rc 2 "$m" run --target in-process:dmc16 --profile missing.json
  expect_rc 2 "$m" run --target in-process:dmc16 --no-such-option
  expect_rc 2 "$m" replay adir
  expect_rc 2 "$m" fuzz "$5/fixtures/sessions/dmc16-workflow.jsonl" --profile adir
  expect_rc 2 "$m"
  expect_rc 0 "$m" --help
  expect_rc 0 "$m" run --help
  ;;

# The serial: target keeps its name in the output (it was labelled pty:).
mococheck_cli_serial_target_is_labelled_serial)
  # A PTY from mocosim, reached through the serial: scheme.
  "$sim" dmc16 --pty "$work/dev" --no-pacing >sim.log 2>&1 &
  pids="$pids $!"
  wait_for test -L "$work/dev" || fail "no PTY"
  expect_rc 0 "$m" run --target "serial:$work/dev" --cases 'connect/*' --json r.json
  grep -q "^mococheck: serial:$work/dev" out.txt || fail "console label"
  grep -q "\"target\": \"serial:$work/dev" r.json || fail "JSON label"
  ;;

*)
  echo "unknown test $test_name" >&2
  exit 1
  ;;
esac
cleanup
exit 0
