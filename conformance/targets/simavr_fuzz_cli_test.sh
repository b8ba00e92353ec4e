#!/bin/sh
# `mococheck fuzz` and `mococheck replay` against firmware under simavr, through
# the command line:
#   simavr_fuzz_cli_test.sh TEST MOCOCHECK WORKDIR SOURCE_DIR GOOD_ELF BUG_ELF
# finding_replays: a finding (here the session itself: `pr 1 0` on the firmware
#   with BUG_ZERO_RATE) is reported with its kind and backtrace, saved, and
#   `mococheck replay` of the saved file finds it again, the same kind at the
#   same place; the good firmware passes the same file.
# sigterm_ends_campaign: SIGTERM ends a long campaign with its summary printed
#   and exit 2 (no finding).
# pin_law_replays (a 7th argument: the firmware with FAULT_DIR_WITH_STEP): with
#   --board the golden session itself is a pin-law finding (DFM-PIN-004), saved
#   with a rerun line that carries the board, and `replay --board` finds it
#   again while the good firmware passes; --driver without --board, --board on
#   an emulated device and `replay --board` of a session with a device side are
#   usage errors that name the fix.
# pause_finding_replays (a 7th argument: the firmware with FAULT_LOST_STEP):
#   from a session that asks for the position while the move is under way,
#   the timing mutation (--pause-percent 30) lets the move end and the lost
#   step show (DFM-PIN-001); the saved finding holds its pauses as `pause`
#   events and `replay` waits them out to the same finding; with
#   --pause-percent 0 the same runs find nothing; a share over 60 is a usage
#   error.
set -u
test_name=$1
m=$2
work=$3/$test_name
src=$4
good=$5
bug=$6
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 1
# shellcheck source=../../tools/cli_test_lib.sh
. "$src/tools/cli_test_lib.sh"

case "$test_name" in
finding_replays)
  printf '%s\n' '{"mocosim_session":1,"protocol":"dfmoco","device":"dfmoco-uno","clock":"virtual"}' \
    '{"t_ns":0,"from":"host","hex":"68690d0a"}' \
    '{"t_ns":1000000,"from":"host","hex":"7072203120300d0a"}' >zero.jsonl
  expect_rc 1 "$m" fuzz zero.jsonl --target "simavr:$bug" --runs 5 --crashes found
  grep -q '^FAIL \[division-by-zero\] the firmware stopped: a division by zero: __udivmodsi4' out.txt ||
    fail "no division-by-zero finding"
  at=$(grep -m1 '^  at 0x' out.txt) || fail "no backtrace"
  grep -q '^  called from 0x.*(main+0x' out.txt || fail "the backtrace does not reach main"
  saved=$(sed -n 's/.*; saved: \(found\/mutant-[0-9-]*\.jsonl\)$/\1/p' out.txt | head -1)
  [ -s "$saved" ] || fail "no saved finding ($saved)"
  grep -q "^  rerun: mococheck replay $saved --target simavr:$bug" out.txt || fail "no rerun line"
  expect_rc 1 "$m" replay "$saved" --target "simavr:$bug"
  grep -q '^FAIL \[division-by-zero\]' out.txt || fail "the replay does not find it again"
  grep -qF "$at" out.txt || fail "the replay stops elsewhere than the fuzzer ($at)"
  expect_rc 0 "$m" replay "$saved" --target "simavr:$good"
  grep -q '^result: PASS' out.txt || fail "the good firmware does not pass the finding's session"
  ;;
sigterm_ends_campaign)
  "$m" fuzz "$src/fixtures/sessions/dfmoco-uno-workflow.jsonl" --target "simavr:$good" \
    --seconds 600 --crashes found >out.txt 2>err.txt &
  check=$!
  pids="${pids:-} $check"
  wait_for grep -q 'execs' err.txt || fail "the campaign did not start"
  signal_and_wait TERM "$check"
  [ "$rc" = 2 ] || fail "exit $rc, not 2: $(cat out.txt err.txt)"
  grep -q '^mococheck fuzz: simavr:.* execs in ' out.txt || fail "no summary"
  grep -q '^result: INTERRUPTED by signal 15 (Terminated) after [0-9]* execs, 0 finding' out.txt ||
    fail "no INTERRUPTED result: $(cat out.txt)"
  ;;
pin_law_replays)
  dir_fault=$7
  board="$src/fixtures/boards/own-dfmoco.json"
  golden="$src/fixtures/sessions/dfmoco-uno-workflow.jsonl"
  expect_rc 1 "$m" fuzz "$golden" --target "simavr:$dir_fault" --board "$board" --runs 2 \
    --crashes found
  grep -q '^FAIL \[pin-law\] pin law: DFM-PIN-004 ' out.txt || fail "no pin-law finding"
  saved=$(sed -n 's/.*; saved: \(found\/mutant-[0-9-]*\.jsonl\)$/\1/p' out.txt | head -1)
  [ -s "$saved" ] || fail "no saved finding ($saved)"
  grep -qF "rerun: mococheck replay $saved --target simavr:$dir_fault --board $board" out.txt ||
    fail "the rerun line does not carry the board"
  expect_rc 1 "$m" replay "$saved" --target "simavr:$dir_fault" --board "$board"
  grep -q '^FAIL \[pin-law\] pin law: DFM-PIN-004 ' out.txt || fail "the replay does not find it"
  expect_rc 0 "$m" replay "$saved" --target "simavr:$good" --board "$board" --driver a4988
  grep -q '^result: PASS' out.txt || fail "the good firmware's pins do not pass"
  expect_rc 2 "$m" fuzz "$golden" --target "simavr:$good" --driver a4988 --runs 1
  grep -q -- '--driver needs --board' err.txt || fail "--driver alone: $(cat err.txt)"
  expect_rc 2 "$m" fuzz "$golden" --target in-process:dfmoco --board "$board" --runs 1
  grep -q -- '--board watches the pins of firmware; give --target simavr:FIRMWARE.elf or native:FIRMWARE' err.txt ||
    fail "--board on an emulated device: $(cat err.txt)"
  expect_rc 2 "$m" replay "$golden" --target "simavr:$good" --board "$board"
  grep -q -- 'use mococheck run --board' err.txt || fail "replay --board of a recording"
  ;;
pause_finding_replays)
  lost=$7
  board="$src/fixtures/boards/own-dfmoco.json"
  printf '%s\n' '{"mocosim_session":1,"protocol":"dfmoco","device":"dfmoco-uno","clock":"virtual"}' \
    '{"t_ns":0,"from":"host","text":"hi\r\n","hex":"68690d0a"}' \
    '{"t_ns":1000000,"from":"host","text":"pr 1 20000\r\n","hex":"707220312032303030300d0a"}' \
    '{"t_ns":2000000,"from":"host","text":"mm 1 1500\r\n","hex":"6d6d203120313530300d0a"}' \
    '{"t_ns":3000000,"from":"host","text":"mp 1\r\n","hex":"6d7020310d0a"}' >move.jsonl
  expect_rc 0 "$m" fuzz move.jsonl --target "simavr:$lost" --board "$board" --runs 300 \
    --pause-percent 0
  grep -q '^result: no invariant broken' out.txt || fail "a finding without pauses: $(cat out.txt)"
  expect_rc 1 "$m" fuzz move.jsonl --target "simavr:$lost" --board "$board" --runs 300 \
    --pause-percent 30 --max-failures 1 --crashes found
  grep -q '^FAIL \[pin-law\] pin law: DFM-PIN-001 ' out.txt || fail "no lost step: $(cat out.txt)"
  saved=$(sed -n 's/.*; saved: \(found\/mutant-[0-9-]*\.jsonl\)$/\1/p' out.txt | head -1)
  [ -s "$saved" ] || fail "no saved finding ($saved)"
  grep -q '"event":"pause","ns":250000000' "$saved" || fail "the finding holds no pause: $(cat "$saved")"
  expect_rc 1 "$m" replay "$saved" --target "simavr:$lost" --board "$board"
  grep -q '^the session records no device side: its [0-9]* host write(s) and [0-9]* pause(s)' out.txt ||
    fail "the replay does not count the pauses: $(cat out.txt)"
  grep -q '^FAIL \[pin-law\] pin law: DFM-PIN-001 ' out.txt || fail "the replay does not find it"
  expect_rc 2 "$m" fuzz move.jsonl --target "simavr:$lost" --pause-percent 61 --runs 1
  grep -q -- '--pause-percent: "61" is not a whole number in 0..60' err.txt ||
    fail "--pause-percent 61: $(cat err.txt)"
  ;;
*)
  fail "unknown test $test_name"
  ;;
esac
exit 0
