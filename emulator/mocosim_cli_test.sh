#!/bin/sh
# mocosim's command line against hostile input and hostile surroundings
# (issue 13): each test is one function, run as
#   mocosim_cli_test.sh TEST MOCOSIM WORKDIR SOURCE_DIR
# and registered with CTest under its own name (emulator/CMakeLists.txt).
# Waits are bounded polls for an event (a log line, a file), never timings.
set -u
test_name=$1
sim=$2
work=$3/$test_name
src=$4
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 1
# shellcheck source=../tools/cli_test_lib.sh
. "$src/tools/cli_test_lib.sh"

case "$test_name" in

# SIGHUP (a closed terminal) stops like SIGTERM: exit 0, the recording
# completed, the PTY symlink and the control socket removed.
mocosim_cli_sighup_stops_cleanly_like_sigterm)
  for sig in HUP TERM INT; do
    rm -f rec.jsonl
    "$sim" dmc16 --pty "$work/dev" --record rec.jsonl --control "$work/ctl.sock" >sim.log 2>&1 &
    p=$!
    pids="$pids $p"
    wait_for test -S "$work/ctl.sock" || fail "SIG$sig: no control socket"
    wait_for test -L "$work/dev" || fail "SIG$sig: no PTY link"
    kill -$sig "$p"
    wait "$p"
    rc=$?
    [ "$rc" = 0 ] || fail "SIG$sig: exit $rc, not 0"
    test -s rec.jsonl || fail "SIG$sig: no recording"
    test ! -e rec.jsonl.partial || fail "SIG$sig: recording left partial"
    test ! -L "$work/dev" || fail "SIG$sig: PTY link left behind"
    test ! -e "$work/ctl.sock" || fail "SIG$sig: control socket left behind"
    grep -q "stopping on SIG$sig" sim.log || fail "SIG$sig: not logged"
  done
  ;;

# A SIGTERM sent the moment the PTY link appears (a supervisor stopping a
# device it just started) is caught, not the default death: exit 0, the link
# removed, the recording completed. The signal is sent from a tight poll so
# it lands inside start-up, where the catch must already be in place.
mocosim_cli_sigterm_during_start_up_stops_cleanly)
  for round in 1 2 3 4 5 6 7 8; do
    rm -f rec.jsonl
    "$sim" dmc16 --pty "$work/dev" --record rec.jsonl >sim.log 2>&1 &
    p=$!
    pids="$pids $p"
    n=0
    while ! test -L "$work/dev"; do
      n=$((n + 1))
      [ $n -gt 200000 ] && fail "round $round: no PTY link"
    done
    kill -TERM "$p"
    wait "$p"
    rc=$?
    [ "$rc" = 0 ] || fail "round $round: exit $rc, not 0 (143 is death by SIGTERM)"
    test ! -L "$work/dev" || fail "round $round: PTY link left behind"
    test -s rec.jsonl || fail "round $round: no recording"
  done
  ;;

# A log line to a closed pipe does not kill mocosim: after the reader of its
# stderr is gone it still stops cleanly and completes its recording.
mocosim_cli_closed_log_pipe_does_not_kill_it)
  mkfifo log.fifo
  head -n 1 <log.fifo >first.txt &
  reader=$!
  "$sim" dmc16 --pty "$work/dev" --record rec.jsonl >log.fifo 2>&1 &
  p=$!
  pids="$pids $p"
  wait "$reader"
  test -s first.txt || fail "head read nothing"
  wait_for test -L "$work/dev" || fail "no PTY link"
  # The stop logs several lines, each now a write to a closed pipe.
  kill -TERM "$p"
  wait "$p"
  rc=$?
  [ "$rc" = 0 ] || fail "exit $rc, not 0 (141 is death by SIGPIPE)"
  test -s rec.jsonl || fail "no recording"
  test ! -e rec.jsonl.partial || fail "recording left partial"
  test ! -L "$work/dev" || fail "PTY link left behind"
  ;;

# decode follows a recorded line_switch (the DFMoco lines after it read as
# DFMoco), and one naming no protocol it knows is a problem (--strict: 1)
# that says which protocols it knows, not a silent misreading.
mocosim_cli_decode_follows_a_line_switch_and_flags_an_unknown_one)
  t=$src/tools/wireshark/testdata/stackshot-panel-dfmoco.jsonl
  expect_rc 1 "$sim" decode --strict "$t"
  grep -q "hello: protocol 1, 3 motors" out.txt || fail "the DFMoco hi after the switch not decoded"
  grep -q "1 problem(s)" out.txt || fail "the switch itself counted as a problem"
  head -3 "$t" >bad.jsonl
  echo '{"t_ns": 5, "event": "line_switch", "protocol": "nope", "baud": 0}' >>bad.jsonl
  echo '{"t_ns": 6, "from": "host", "hex": "5510050000eb"}' >>bad.jsonl
  expect_rc 1 "$sim" decode --strict bad.jsonl
  grep -q "names no protocol this mocosim knows" out.txt || fail "unknown switch not flagged"
  grep -q "stackshot-dfmoco" out.txt || fail "the known protocols not named"
  [ "$(grep -c "CC_RAIL_STATUS read axis=X" out.txt)" = 2 ] || fail "traffic after it not read as before"
  expect_rc 0 "$sim" decode bad.jsonl
  ;;

# Every parse error is 2, never CLI11's own codes (105 for a missing or
# directory file); --help and --version are 0.
mocosim_cli_parse_errors_exit_2_and_help_exits_0)
  mkdir adir
  s=$src/fixtures/sessions/dmc16-boom-move.jsonl
  p=$src/fixtures/profiles/dmc16-boom.json
  expect_rc 2 "$sim" dmc16 --pty "$work/dev" --profile adir
  expect_rc 2 "$sim" dmc16 --pty "$work/dev" --profile missing.json
  expect_rc 2 "$sim" dmc16 --pty "$work/dev" --scenario adir
  expect_rc 2 "$sim" dmc16 --pty "$work/dev" --scenario missing.json
  expect_rc 2 "$sim" decode adir
  expect_rc 2 "$sim" decode missing.jsonl
  expect_rc 2 "$sim" run adir
  expect_rc 2 "$sim" run missing.json
  expect_rc 2 "$sim" dmc16 --no-such-option
  expect_rc 2 "$sim" dmc16 --pty "$work/dev" --log-level loud
  # An empty file option (an unset shell variable) is refused, not ignored.
  for args in "--record" "--control"; do
    expect_rc 2 "$sim" dmc16 --pty "$work/dev" $args ""
    grep -q -- "$args: needs a path" err.txt || fail "empty $args accepted"
  done
  expect_rc 2 "$sim" stackshot3x --pty "$work/dev" --state ""
  expect_rc 2 "$sim"
  for args in "--every-ms nan" "--every-ms 0" "--from-s inf" "--to-s -1" "--tail-s 1e400" \
              "--tail-s 3601"; do
    opt=${args%% *}
    # shellcheck disable=SC2086
    expect_rc 2 "$sim" plot "$s" --profile "$p" -o x.svg $args
    grep -q -- "$opt" err.txt || fail "the message does not name $opt"
  done
  test ! -e x.svg || fail "a plot was written"
  test ! -L "$work/dev" || fail "a PTY link was left"
  expect_rc 0 "$sim" --help
  expect_rc 0 "$sim" dmc16 --help
  expect_rc 0 "$sim" --version
  ;;

# A number beyond a double in a profile names the file and the field; a run
# file's errors speak of the run file and docs/run-files.md.
mocosim_cli_profile_and_run_file_errors_name_the_file_and_field)
  printf '{"motor_count": 1e400}\n' >big.json
  expect_rc 2 "$sim" dmc16 --pty "$work/dev" --profile big.json
  grep -q 'big.json' err.txt || fail "no file name"
  grep -q '"motor_count"' err.txt || fail "no field name"
  grep -q 'json.exception' err.txt && fail "a raw json exception"
  printf '{"devices": [{"endpoint": "tcp:0", "modle": "dmc16"}]}\n' >run.json
  expect_rc 2 "$sim" run run.json
  grep -q 'run file' err.txt || fail "does not say run file"
  grep -q 'docs/run-files.md' err.txt || fail "does not point to docs/run-files.md"
  grep -q 'profile' err.txt && fail "speaks of a profile"
  printf '{"devices": [{"endpoint": "tcp:0", "no_pacing": 1e999}]}\n' >run2.json
  expect_rc 2 "$sim" run run2.json
  grep -q 'devices\[\].no_pacing' err.txt || fail "run file: no field name"
  ;;

# `mocosim export --pcapng`: a golden session becomes a capture (SHB magic,
# one packet per chunk); a missing or damaged session, a directory or the
# session itself as the output are refused with exit 2 and nothing written;
# a planted symlink's target is replaced whole, not written through; a cut
# session exports the lines before the cut with a warning; /dev/null works.
mocosim_cli_export_pcapng_refuses_bad_paths_and_keeps_what_is_there)
  session="$src/fixtures/sessions/dmc16-handshake.jsonl"
  expect_rc 0 "$sim" export --pcapng "$session" -o cap.pcapng
  grep -q '23 packet(s)' out.txt || fail "no packet count"
  [ "$(od -An -tx1 -N4 cap.pcapng | tr -d ' ')" = 0a0d0d0a ] || fail "not a pcapng section"
  expect_rc 2 "$sim" export --pcapng missing.jsonl -o x.pcapng
  grep -q 'missing.jsonl' err.txt || fail "missing session not named"
  test ! -e x.pcapng || fail "an output for a missing session"
  mkdir adir
  expect_rc 2 "$sim" export --pcapng "$session" -o adir
  grep -q 'directory' err.txt || fail "directory output not explained"
  cp "$session" s.jsonl
  expect_rc 2 "$sim" export --pcapng s.jsonl -o s.jsonl
  cmp -s s.jsonl "$session" || fail "the session was overwritten"
  printf 'not json\n' >bad.jsonl
  expect_rc 2 "$sim" export --pcapng bad.jsonl -o bad.pcapng
  grep -q 'bad.jsonl:1' err.txt || fail "damaged session: line not named"
  test ! -e bad.pcapng || fail "an output for a damaged session"
  echo keep >victim.txt
  ln -s victim.txt link.pcapng
  expect_rc 0 "$sim" export --pcapng "$session" -o link.pcapng
  cmp -s victim.txt cap.pcapng || fail "the symlink's target is not the capture"
  test -L link.pcapng || fail "the symlink was replaced"
  head -c 700 "$session" >cut.jsonl
  expect_rc 0 "$sim" export --pcapng cut.jsonl -o cut.pcapng
  grep -q 'cut short' err.txt || fail "cut session: no warning"
  expect_rc 0 "$sim" export --pcapng "$session" -o /dev/null
  expect_rc 2 "$sim" export "$session" -o y.pcapng
  ;;

# An output path that is an input or a path mocosim serves (a PTY's link,
# the control socket), by any spelling (./, a/../, a symlink), is refused at
# start with exit 2, the message naming both options and the fix; nothing is
# left behind. (A recording into the device's own PTY used to block mocosim
# on its own port, deaf to signals.) `timeout` only keeps a regression from
# hanging the suite.
mocosim_cli_output_equal_to_an_input_or_a_served_path_is_refused)
  # refused WANT1 WANT2 ARGS...: exit 2, both named, no PTY link left.
  refused() {
    w1=$1
    w2=$2
    shift 2
    expect_rc 2 timeout -s KILL 60 "$sim" "$@"
    grep -q -- "$w1" err.txt || fail "$*: $w1 not named"
    grep -q -- "$w2" err.txt || fail "$*: $w2 not named"
    grep -q "give" err.txt || fail "$*: no fix given"
    test ! -e "$work/p" || fail "$*: a PTY link was left"
  }
  mkdir sub
  ln -s "$work/p" alias
  cp "$src/fixtures/profiles/dmc16-boom.json" prof.json
  for model in dfmoco dmc16; do
    refused --record --pty "$model" --pty "$work/p" --record "$work/p"
  done
  refused --record --pty dfmoco --pty "$work/p" --record "$work/sub/../p"
  refused --record --pty dfmoco --pty "$work/p" --record ./p
  refused --record --pty dfmoco --pty "$work/p" --record alias
  refused --vcd --pty dmc16 --pty "$work/p" --vcd "$work/p"
  refused --state --pty stackshot3x --pty "$work/p" --state "$work/p"
  refused --record --control dmc16 --pty "$work/p" --control "$work/c.sock" --record c.sock
  refused --record --profile dmc16 --pty "$work/p" --profile prof.json --record ./prof.json
  cmp -s prof.json "$src/fixtures/profiles/dmc16-boom.json" || fail "the profile was written"
  refused --pty --profile dmc16 --pty "$work/prof.json" --profile prof.json
  printf '{"events": []}\n' >scen.json
  refused --record --scenario dmc16 --pty "$work/p" --scenario scen.json --record scen.json
  # A run file: the keys are named; the run file itself is an input.
  printf '{"devices": [{"name": "a", "endpoint": "pty:p", "record": "p"}]}\n' >run.json
  refused '"record"' '"endpoint"' run run.json
  printf '{"devices": [{"name": "a", "endpoint": "pty:p", "record": "run2.json"}]}\n' >run2.json
  refused '"record"' 'the run file' run run2.json
  grep -q devices run2.json || fail "the run file was written"
  # export and plot: the session by another spelling.
  cp "$src/fixtures/sessions/dmc16-boom-move.jsonl" s.jsonl
  expect_rc 2 "$sim" export --pcapng s.jsonl -o sub/../s.jsonl
  grep -q -- "--output" err.txt || fail "export: --output not named"
  expect_rc 2 "$sim" plot s.jsonl --profile prof.json -o ./sub/../prof.json
  grep -q -- "--output" err.txt || fail "plot: --output not named"
  cmp -s s.jsonl "$src/fixtures/sessions/dmc16-boom-move.jsonl" || fail "the session was written"
  cmp -s prof.json "$src/fixtures/profiles/dmc16-boom.json" || fail "the profile was written"
  ;;

# `mocosim export --pcapng SESSION` without -o writes beside the session and
# says where; when that folder cannot be written it fails with exit 2 naming
# -o as the fix, and leaves nothing there. (As root every folder is
# writable: mocosim then runs as nobody.)
mocosim_cli_export_without_o_says_where_and_names_o_when_it_cannot)
  mkdir ro
  cp "$src/fixtures/sessions/dmc16-handshake.jsonl" ro/s.jsonl
  expect_rc 0 "$sim" export --pcapng ro/s.jsonl
  grep -q "wrote ro/s.pcapng" out.txt || fail "does not say where it wrote"
  test -s ro/s.pcapng || fail "no capture beside the session"
  rm ro/s.pcapng
  chmod 555 ro
  as_user=""
  [ "$(id -u)" = 0 ] && as_user="setpriv --reuid=65534 --regid=65534 --clear-groups"
  # shellcheck disable=SC2086
  expect_rc 2 $as_user "$sim" export --pcapng ro/s.jsonl
  grep -q -- "-o FILE" err.txt || fail "the fix -o is not named"
  grep -q "ro/s.pcapng" err.txt || fail "the path it could not write is not named"
  [ "$(ls ro)" = s.jsonl ] || fail "something was left beside the session: $(ls ro)"
  chmod 755 ro
  ;;

*)
  echo "unknown test $test_name" >&2
  exit 1
  ;;
esac
cleanup
exit 0
