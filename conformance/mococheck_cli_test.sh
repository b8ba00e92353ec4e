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
src=$5
. "$src/tools/cli_test_lib.sh"

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
    # The case under way is named (null only if the signal fell between cases).
    grep -q '"interrupted_case": ' r.json || fail "SIG$sig: JSON names no interrupted case"
    test -s r.xml || fail "SIG$sig: no JUnit report"
    # Progress went to stderr as the cases started.
    grep -q '^mococheck: \[1/[0-9]*\] connect/' err.txt || fail "SIG$sig: no progress on stderr"
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

# No PASS without evidence: a PTY that reads everything and answers nothing is
# a target error (2) for every protocol, subset and shard; a second mococheck
# on a port in use is refused; a selection that judges no rule is NO VERDICT
# (2); each glob of --cases / --rules must select something.
mococheck_cli_no_pass_without_evidence)
  python3 -c '
import os, pty, sys
master, slave = pty.openpty()
os.symlink(os.ttyname(slave), sys.argv[1])
while True:
    os.read(master, 4096)
' "$work/silent" >silent.log 2>&1 &
  pids="$pids $!"
  wait_for test -L "$work/silent" || fail "no silent PTY"
  for args in "--protocol dmc --cases motor/*" "--protocol dfmoco --cases motor/*" \
              "--protocol dmc --shard 5/8" "--protocol dmc --shard 7/8" \
              "--protocol dfmoco --shard 3/8" "--protocol stackshot --shard 2/8"; do
    # shellcheck disable=SC2086
    expect_rc 2 "$m" run --target "pty:$work/silent" $args --answer-timeout-ms 100 \
      --junit r.xml --json r.json
    grep -q '^result: TARGET ERROR' out.txt || fail "no TARGET ERROR for $args"
    grep -q 'sent nothing in answer to two introductions' out.txt ||
      fail "the console does not say why: $args"
    grep -q '"exit_code": 2' r.json || fail "JSON exit_code is not 2: $args"
    grep -q '<error message="target error' r.xml || fail "JUnit has no error: $args"
  done
  # Two runs on one emulated PTY: the second is refused, the first goes on.
  "$sim" dmc16 --pty "$work/dmc" >sim.log 2>&1 &
  sim_pid=$!
  pids="$pids $sim_pid"
  wait_for test -L "$work/dmc" || fail "no PTY"
  # Cases of a few seconds' motion: the first run still holds the port when
  # the second starts, however loaded the machine (connect/* alone can end
  # before the second run opens the port).
  "$m" run --target "pty:$work/dmc" --cases 'motor/move,motor/stop' >first.txt 2>first-err.txt &
  first=$!
  pids="$pids $first"
  wait_for grep -q '^mococheck: \[1/' first-err.txt || fail "the first run did not start"
  expect_rc 2 "$m" run --target "pty:$work/dmc" --cases 'connect/*' -q
  grep -q 'in use by another program' err.txt || fail "the second run was not refused"
  wait "$first"
  rc=$?
  [ "$rc" = 0 ] || fail "the first run: exit $rc, not 0"
  grep -q '^result: PASS' first.txt || fail "the first run did not pass"
  kill -TERM "$sim_pid"
  # A selection whose cases judge none of its rules has no verdict.
  expect_rc 2 "$m" run --target in-process:dmc16 --rules DMC-RT-029 --cases 'motor/*' \
    --junit nv.xml
  grep -q '^result: NO VERDICT' out.txt || fail "no NO VERDICT"
  grep -q '<error message="no rule was judged' nv.xml || fail "JUnit has no error"
  # Every glob of a list must select something.
  expect_rc 2 "$m" run --target in-process:dmc16 --cases 'motor/*,nonexistent/*'
  grep -q "'nonexistent/\*' selects no" err.txt || fail "the empty glob is not named"
  expect_rc 2 "$m" run --target in-process:dmc16 --rules 'DMC-HI-*,DMC-NOPE-*'
  grep -q "'DMC-NOPE-\*' matches no" err.txt || fail "the empty rule glob is not named"
  expect_rc 2 "$m" run --target in-process:dmc16 --cases ','
  grep -q 'holds no glob' err.txt || fail "a list of no globs accepted"
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
# One report that cannot be written (a full disk) does not stop the others:
# each failure is named with its option, the rest are written, exit 2.
mococheck_cli_a_failing_report_does_not_stop_the_others)
  [ -w /dev/full ] || fail "no /dev/full on this machine"
  expect_rc 2 "$m" run --target in-process:dmc16 --cases 'connect/*' -q \
    --junit /dev/full --json r.json --html r.html
  grep -q 'could not write --junit /dev/full' err.txt || fail "the failing --junit is not named"
  grep -q 'written: --html r.html, --json r.json' err.txt || fail "the reports written are not named"
  test -s r.json && test -s r.html || fail "the other reports were not written"
  grep -q '"exit_code": 0' r.json || fail "the JSON report does not carry the verdict"
  grep -q '^result: PASS' out.txt || fail "no verdict on the console"
  expect_rc 2 "$m" run --target in-process:dmc16 --cases 'connect/hi' -q \
    --json /dev/full --junit r.xml
  grep -q 'could not write --json /dev/full' err.txt || fail "the failing --json is not named"
  test -s r.xml || fail "the JUnit report was not written"
  ;;

mococheck_cli_serial_target_is_labelled_serial)
  # A PTY from mocosim, reached through the serial: scheme.
  "$sim" dmc16 --pty "$work/dev" --no-pacing >sim.log 2>&1 &
  pids="$pids $!"
  wait_for test -L "$work/dev" || fail "no PTY"
  expect_rc 0 "$m" run --target "serial:$work/dev" --cases 'connect/*' --json r.json
  grep -q "^mococheck: serial:$work/dev" out.txt || fail "console label"
  grep -q "\"target\": \"serial:$work/dev" r.json || fail "JSON label"
  ;;

# --board, --driver and --vcd: refused with the fix before anything runs.
mococheck_cli_pin_options_are_checked_before_the_run)
  board=$src/fixtures/boards/own-dfmoco.json
  expect_rc 2 "$m" run --target in-process:dfmoco --vcd x.vcd
  grep -q -- "--vcd needs --board" err.txt || fail "--vcd without --board"
  expect_rc 2 "$m" run --target in-process:dfmoco --board "$board"
  grep -q "only on a firmware target (--board needs --target simavr:PATH.elf or --target native:PATH)" err.txt || fail "--board on an in-process target"
  expect_rc 2 "$m" run --target in-process:dfmoco --board "$board" --driver l298
  grep -q "not a known driver; give one of a4988, drv8825, tmc2209" err.txt || fail "driver"
  printf '{"board": "x", "motors": [{"step": "PD4", "dir": "PD4"}]}' >twice.json
  expect_rc 2 "$m" run --target in-process:dfmoco --board twice.json
  grep -q "PD4 is named twice" err.txt || fail "a pin named twice"
  expect_rc 2 "$m" run --target in-process:dfmoco --board /dev/null
  grep -q "board profile" err.txt || fail "an empty board"
  test ! -e x.vcd || fail "a VCD was written"
  ;;

# mocosim --vcd: the step model's pulses, read back by sigrok-cli -I vcd, reach the
# position motor 1 reported at rest (motor/move: 6000, then back to where it was;
# the model's report of that return may come after the case, FACTS DFMoco).
mocosim_vcd_read_by_sigrok_counts_the_reported_steps)
  "$sim" dfmoco --pty "$work/dev" --vcd model.vcd >sim.log 2>&1 &
  sim_pid=$!
  pids="$pids $sim_pid"
  wait_for test -L "$work/dev" || fail "no PTY"
  expect_rc 0 "$m" run --target "pty:$work/dev" --protocol dfmoco --cases 'motor/move' -q \
    --json run.json
  kill -TERM "$sim_pid"
  wait "$sim_pid" || fail "mocosim did not stop cleanly"
  [ -s model.vcd ] || fail "no VCD written"
  sigrok-cli -I vcd:downsample=1000 -i model.vcd -O vcd -o back.vcd >sigrok.txt 2>&1 ||
    fail "sigrok-cli could not read model.vcd"
  steps=$(awk '
    /^\$var/ { name[$4] = $5; next }
    /^[#01]/ { for (i = 1; i <= NF; i++) {
        f = $i; v = substr(f, 1, 1); id = substr(f, 2)
        if (v == "#") continue
        if (name[id] == "m1_dir") dir = v
        if (name[id] == "m1_step") {
          if (v == 1 && step == 0) { n += (dir == 1 ? 1 : -1); rises++; if (n > hi) hi = n }
          step = v } } }
    END { print n + 0, hi + 0, rises + 0 }' back.vcd)
  reported=$(python3 -c '
import json, sys
c = json.load(open(sys.argv[1]))["cases"][0]
print(c["position_range"]["1"][1])
' run.json)
  echo "sigrok: final, highest, rising edges: $steps; highest reported: $reported"
  set -- $steps
  [ "$2" = "$reported" ] || fail "sigrok counts up to $2 steps; mp 1 said $reported"
  [ "$1" = 0 ] || fail "sigrok counts motor 1 back at $1, not 0"
  [ "$3" = 12000 ] || fail "sigrok counts $3 STEP pulses, not 12000 (6000 out, 6000 back)"
  ;;

# In-process runs write their reports, atomically (no partial file left).
mococheck_cli_in_process)
  expect_rc 0 "$m" run --target in-process:dmc16 -q --junit mococheck.xml --json mococheck.json
  test -s mococheck.xml && test -s mococheck.json || fail "reports missing"
  test ! -e mococheck.xml.partial || fail "a partial report was left"
  ;;
mococheck_cli_stackshot_in_process)
  expect_rc 0 "$m" run --target in-process:stackshot3x -q --junit ss.xml --json ss.json
  test -s ss.xml || fail "no JUnit report"
  grep -q '"protocol": "stackshot"' ss.json || fail "the JSON report names no stackshot protocol"
  ;;
mococheck_cli_dfmoco_in_process)
  expect_rc 0 "$m" run --target in-process:dfmoco -q --junit dfm.xml --json dfm.json
  test -s dfm.xml && test -s dfm.json || fail "reports missing"
  ;;
# A StackShot 3X in DfMoco mode (stackshot-protocol.txt section 3) certified
# through --protocol dfmoco: the StackShot dialect detected from `hi 1 3 1.2.6`
# and recorded in the JSON report; a bad --dialect is a usage error.
mococheck_cli_stackshot_dfmoco_in_process)
  expect_rc 0 "$m" run --target in-process:stackshot3x --protocol dfmoco --json ss.json
  grep -q '^result: PASS' out.txt || fail "no PASS verdict"
  grep -q '"dialect": "stackshot3x"' ss.json || fail "the JSON report names no stackshot3x dialect"
  grep -q 'stackshot/mp-all' out.txt || fail "the stackshot cases did not run"
  expect_rc 0 "$m" run --target in-process:stackshot3x --protocol dfmoco --dialect stackshot3x \
    -q --cases 'stackshot/*' --json forced.json
  grep -q '"dialect": "stackshot3x"' forced.json || fail "--dialect stackshot3x not recorded"
  expect_rc 0 "$m" run --target in-process:dfmoco -q --json sketch.json
  grep -q '"dialect": "sketch"' sketch.json || fail "the sketch's dialect not recorded"
  expect_rc 2 "$m" run --target in-process:stackshot3x --protocol dfmoco --dialect arduino
  grep -q 'give auto' err.txt || fail "the bad --dialect is not explained"
  expect_rc 2 "$m" run --target in-process:dmc16 --dialect sketch
  grep -q 'applies to --protocol dfmoco only' err.txt || fail "--dialect on DMC not refused"
  expect_rc 0 "$m" run --help
  grep -q -- '--dialect' out.txt || fail "--help does not list --dialect"
  grep -q -- '--protocol dfmoco: auto' out.txt || fail "--help does not list the DFMoco dialects"
  ;;
# `mocosim stackshot3x` on a PTY, switched to DfMoco mode by the binary
# protocol's CC_RAIL_CONFIG_GLOBAL_MODE write (0x109E, GLOBAL_MODE_MOTION_DFMOCO
# = 8; acknowledged in the binary dialect, then the line speaks DfMoco), then
# certified through --protocol dfmoco: the StackShot dialect detected.
mococheck_cli_stackshot_dfmoco_pty)
  "$sim" stackshot3x --pty "$work/dev" --state "$work/nvm.json" >sim.log 2>&1 &
  sim_pid=$!
  pids="$pids $sim_pid"
  wait_for test -L "$work/dev" || fail "no PTY"
  stty -F "$work/dev" raw -echo || fail "stty failed on the PTY"
  printf '\125\020\236\001\001\010\000' >"$work/dev"
  timeout 1 cat "$work/dev" >ack.bin
  [ "$(od -An -tx1 -N1 ack.bin | tr -d ' ')" = aa ] || fail "no binary acknowledgement"
  expect_rc 0 "$m" run --target "pty:$work/dev" --protocol dfmoco -q --json pty.json \
    --cases 'connect/hi,stackshot/mp-all,stackshot/pulse-rate,stackshot/np-zm'
  grep -q '^result: PASS' out.txt || fail "no PASS verdict"
  grep -q '"dialect": "stackshot3x"' pty.json || fail "the JSON report names no stackshot3x dialect"
  kill -TERM "$sim_pid"
  wait "$sim_pid" || fail "mocosim did not stop cleanly"
  ;;
mococheck_cli_dfmoco_mega)
  expect_rc 0 "$m" run --target in-process:dfmoco -q \
    --profile "$src/fixtures/profiles/dfmoco-mega.json"
  ;;

# Usage errors exit 2: an unknown target kind, a protocol the model does not
# speak, no target, a shard out of range.
mococheck_cli_usage_errors)
  expect_rc 2 "$m" run --target ftp:x
  expect_rc 2 "$m" run --target in-process:dmc16 --protocol dfmoco
  grep -q 'does not match in-process:dmc16' err.txt || fail "the mismatch is not named"
  expect_rc 2 "$m" run
  expect_rc 2 "$m" run --target in-process:dmc16 --shard 0/2
  ;;

# The DMC-16 driving the Bullet boom rig passes every rule, the virtual-axis
# family included (a move, a stop and a jog run through the physical rig).
mococheck_cli_dmc16_boom_rig)
  expect_rc 0 "$m" run --target in-process:dmc16 -q --json boom.json \
    --profile "$src/fixtures/profiles/dmc16-boom.json"
  for r in 001 002 003 007 008; do
    grep -A2 "\"id\": \"DMC-VIRT-$r\"" boom.json | grep -q '"status": "pass"' ||
      fail "DMC-VIRT-$r did not pass"
  done
  ;;

# Reports into a FIFO (as into /dev/null) are written in place: the FIFO
# stays a FIFO and its reader gets the report (docs/files.md).
mococheck_cli_junit_into_a_fifo_keeps_the_fifo)
  mkfifo junit || fail "mkfifo"
  cat junit >got &
  pids="$pids $!"
  expect_rc 0 "$m" run --target in-process:dmc16 -q --junit junit
  wait_for grep -q '</testsuites>' got || fail "the FIFO's reader got no whole report"
  test -p junit || fail "the FIFO was replaced"
  grep -q '<testsuites' got || fail "no JUnit report through the FIFO"
  ;;

# Outputs that cannot be written, or would overwrite an input or each other,
# are refused before the run (exit 2, naming the path); /dev/zero as a
# profile is refused instead of read without end.
mococheck_cli_bad_outputs_and_inputs_refused_before_the_run)
  mkdir outdir && echo '{}' >p.json
  expect_rc 2 "$m" run --target in-process:dmc16 -q --junit outdir
  grep -q 'is a directory' err.txt || fail "a directory as --junit is not named"
  expect_rc 2 "$m" run --target in-process:dmc16 -q --profile p.json --json p.json
  grep -q 'is the --profile' err.txt || fail "--json over the profile is not named"
  expect_rc 2 "$m" run --target in-process:dmc16 -q --junit r --json r
  grep -q 'is also --junit' err.txt || fail "two reports to one file is not named"
  expect_rc 2 "$m" run --target in-process:dmc16 -q --profile /dev/zero
  grep -q 'character device' err.txt || fail "/dev/zero as a profile is not named"
  test "$(cat p.json)" = '{}' || fail "the profile was written"
  test ! -e r || fail "a report was written although the run was refused"
  ;;

# `mococheck cases` lists each protocol's cases.
mococheck_cli_cases)
  expect_rc 0 "$m" cases
  grep -q '^rt/live-run ' out.txt || fail "no rt/live-run in the DMC cases"
  ;;
mococheck_cli_stackshot_cases)
  expect_rc 0 "$m" cases --protocol stackshot
  grep -q '^curve/play ' out.txt || fail "no curve/play in the StackShot cases"
  ;;
mococheck_cli_dfmoco_cases)
  expect_rc 0 "$m" cases --protocol dfmoco
  grep -q '^random/sequence ' out.txt || fail "no random/sequence in the DFMoco cases"
  ;;

# The golden sessions replay against fresh devices, and a short fuzz run per
# protocol breaks no invariant.
mococheck_replay_golden_sessions)
  for s in dmc16-workflow dmc16-live-run dfmoco-uno-workflow stackshot3x-workflow; do
    expect_rc 0 "$m" replay "$src/fixtures/sessions/$s.jsonl"
    grep -q '^result: MATCH' out.txt || fail "$s does not replay byte for byte"
  done
  ;;
mococheck_fuzz_every_protocol)
  for s in dmc16-workflow dfmoco-uno-workflow stackshot3x-workflow; do
    expect_rc 0 "$m" fuzz "$src/fixtures/sessions/$s.jsonl" --runs 2000 --crashes fuzz-crashes
  done
  ;;
# Fuzz and replay usage errors exit 2: a real device to fuzz, sessions of two
# protocols, a missing session, a model that speaks another protocol.
mococheck_fuzz_replay_usage_errors)
  f=$src/fixtures/sessions
  expect_rc 2 "$m" fuzz "$f/dmc16-workflow.jsonl" --target tcp:127.0.0.1:1
  expect_rc 2 "$m" fuzz "$f/dmc16-workflow.jsonl" "$f/dfmoco-uno-workflow.jsonl"
  expect_rc 2 "$m" replay /nonexistent.jsonl
  expect_rc 2 "$m" replay "$f/dmc16-workflow.jsonl" --target in-process:dfmoco
  grep -q "does not speak the session's protocol dmc" err.txt || fail "the mismatch is not named"
  ;;

# docs/rules.md is what `mococheck rules --markdown` prints.
mococheck_rules_markdown_matches_docs)
  "$m" rules --markdown >rules.md || fail "mococheck rules failed"
  cmp rules.md "$src/docs/rules.md" || fail "docs/rules.md is stale: mococheck rules --markdown > docs/rules.md"
  ;;

*)
  echo "unknown test $test_name" >&2
  exit 1
  ;;
esac
cleanup
exit 0
