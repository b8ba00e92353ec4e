# Helpers shared by the command-line test scripts (emulator/mocosim_cli_test.sh,
# conformance/mococheck_cli_test.sh), sourced after they cd into their work
# folder. Waits are bounded polls for an event, never timings.

# Background processes to kill when the test ends.
pids=""
cleanup() {
  for p in $pids; do kill -9 "$p" 2>/dev/null; done
}
trap cleanup EXIT
# fail MESSAGE: prints it and every *.txt / *.log of the work folder, exits 1.
fail() {
  echo "FAIL: $*" >&2
  for f in *.txt *.log; do [ -f "$f" ] && { echo "--- $f" >&2; cat "$f" >&2; }; done
  cleanup
  exit 1
}
# wait_for CMD...: polls CMD up to 600 times, 0.1 s apart.
wait_for() {
  i=0
  while ! "$@" >/dev/null 2>&1; do
    i=$((i + 1))
    [ $i -gt 600 ] && return 1
    sleep 0.1
  done
}
# signal_and_wait SIGNAL PID: sends SIGNAL to PID, waits (bounded) until it has
# ended and sets rc to its exit status; fails when it is still running.
signal_and_wait() {
  kill "-$1" "$2"
  wait_for sh -c "! kill -0 $2 2>/dev/null" || fail "still running 60 s after SIG$1"
  wait "$2"
  rc=$?
}
# expect_rc WANT CMD...: runs CMD (stdout out.txt, stderr err.txt), checks its status.
expect_rc() {
  want=$1
  shift
  "$@" >out.txt 2>err.txt
  got=$?
  [ "$got" = "$want" ] || fail "exit $got, not $want: $*"
}
