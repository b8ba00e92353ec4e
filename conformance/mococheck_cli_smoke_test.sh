#!/bin/sh
# mococheck's command line, the common paths: exit 0 with reports written, 2 on
# a usage or target error; replay and fuzz of the golden sessions; the rules
# page. Each test is one case, run as
#   mococheck_cli_smoke_test.sh TEST MOCOCHECK WORKDIR SOURCE_DIR
# and registered with CTest under its own name (conformance/CMakeLists.txt).
# Hostile input and hostile targets: mococheck_cli_test.sh.
set -u
test_name=$1
m=$2
work=$3/$test_name
src=$4
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 1
# shellcheck source=../tools/cli_test_lib.sh
. "$src/tools/cli_test_lib.sh"
sessions=$src/fixtures/sessions
profiles=$src/fixtures/profiles

case "$test_name" in

mococheck_cli_in_process)
  "$m" run --target in-process:dmc16 -q --junit mococheck.xml --json mococheck.json ||
    fail "exit $?, not 0"
  test -s mococheck.xml || fail "no JUnit report"
  test -s mococheck.json || fail "no JSON report"
  test ! -e mococheck.xml.partial || fail "a partial JUnit report is left"
  ;;

mococheck_cli_usage_errors)
  expect_rc 2 "$m" run --target ftp:x
  expect_rc 2 "$m" run --target in-process:dmc16 --protocol dfmoco
  expect_rc 2 "$m" run
  expect_rc 2 "$m" run --target in-process:dmc16 --shard 0/2
  ;;

# The DMC-16 driving the Bullet boom rig passes every rule, the virtual-axis
# family included (a move, a stop and a jog run through the physical rig).
mococheck_cli_dmc16_boom_rig)
  "$m" run --target in-process:dmc16 --profile "$profiles/dmc16-boom.json" -q --json boom.json ||
    fail "exit $?, not 0"
  for r in 001 002 003 007 008; do
    grep -A2 '"id": "DMC-VIRT-'$r'"' boom.json | grep -q '"status": "pass"' ||
      fail "DMC-VIRT-$r does not pass"
  done
  ;;

# Reports into a FIFO (as into /dev/null) are written in place: the FIFO
# stays a FIFO and its reader gets the report (docs/files.md).
mococheck_cli_junit_into_a_fifo_keeps_the_fifo)
  mkfifo junit || fail "mkfifo"
  cat junit >got &
  pids="$pids $!"
  "$m" run --target in-process:dmc16 -q --junit junit
  r=$?
  for i in 1 2 3 4 5 6 7 8 9 10; do
    grep -q '</testsuites>' got 2>/dev/null && break
    sleep 0.2
  done
  test "$r" = 0 || fail "exit $r, not 0"
  test -p junit || fail "the FIFO is no longer a FIFO"
  grep -q '<testsuites' got || fail "the FIFO's reader got no report"
  ;;

# Outputs that cannot be written, or would overwrite an input or each other,
# are refused before the run (exit 2, naming the path); /dev/zero as a
# profile is refused instead of read without end.
mococheck_cli_bad_outputs_and_inputs_refused_before_the_run)
  mkdir d && echo '{}' >d/p.json
  expect_rc 2 "$m" run --target in-process:dmc16 -q --junit d
  grep -q 'is a directory' err.txt || fail "a directory as --junit: not named"
  expect_rc 2 "$m" run --target in-process:dmc16 -q --profile d/p.json --json d/p.json
  grep -q 'is the --profile' err.txt || fail "--json onto the --profile: not named"
  expect_rc 2 "$m" run --target in-process:dmc16 -q --junit d/r --json d/r
  grep -q 'is also --junit' err.txt || fail "--json onto --junit: not named"
  expect_rc 2 "$m" run --target in-process:dmc16 -q --profile /dev/zero
  grep -q 'character device' err.txt || fail "/dev/zero as --profile: not named"
  test "$(cat d/p.json)" = '{}' || fail "the profile was overwritten"
  test ! -e d/r || fail "d/r was written"
  ;;

mococheck_cli_cases)
  "$m" cases | grep -q '^rt/live-run ' || fail "no rt/live-run case"
  ;;

# Replay of the golden sessions, a short fuzz run per protocol, and the fuzz
# and replay usage errors (exit 2).
mococheck_replay_golden_sessions)
  for s in dmc16-workflow dfmoco-uno-workflow stackshot3x-workflow; do
    "$m" replay "$sessions/$s.jsonl" | grep -q '^result: MATCH' || fail "$s does not match"
  done
  ;;

mococheck_fuzz_every_protocol)
  for s in dmc16-workflow dfmoco-uno-workflow stackshot3x-workflow; do
    "$m" fuzz "$sessions/$s.jsonl" --runs 2000 --crashes fuzz-crashes || fail "$s: exit $?"
  done
  ;;

mococheck_fuzz_replay_usage_errors)
  expect_rc 2 "$m" fuzz "$sessions/dmc16-workflow.jsonl" --target tcp:127.0.0.1:1
  expect_rc 2 "$m" fuzz "$sessions/dmc16-workflow.jsonl" "$sessions/dfmoco-uno-workflow.jsonl"
  expect_rc 2 "$m" replay /nonexistent.jsonl
  expect_rc 2 "$m" replay "$sessions/dmc16-workflow.jsonl" --target in-process:dfmoco
  ;;

mococheck_cli_stackshot_in_process)
  "$m" run --target in-process:stackshot3x -q --junit ss.xml --json ss.json ||
    fail "exit $?, not 0"
  test -s ss.xml || fail "no JUnit report"
  grep -q '"protocol": "stackshot"' ss.json || fail "the JSON report is not of stackshot"
  ;;

mococheck_cli_stackshot_cases)
  "$m" cases --protocol stackshot | grep -q '^curve/play ' || fail "no curve/play case"
  ;;

mococheck_cli_dfmoco_in_process)
  "$m" run --target in-process:dfmoco -q --junit mococheck-dfmoco.xml --json mococheck-dfmoco.json ||
    fail "exit $?, not 0"
  test -s mococheck-dfmoco.xml || fail "no JUnit report"
  test -s mococheck-dfmoco.json || fail "no JSON report"
  ;;

mococheck_cli_dfmoco_mega)
  "$m" run --target in-process:dfmoco --profile "$profiles/dfmoco-mega.json" -q ||
    fail "exit $?, not 0"
  ;;

mococheck_cli_dfmoco_cases)
  "$m" cases --protocol dfmoco | grep -q '^random/sequence ' || fail "no random/sequence case"
  ;;

mococheck_rules_markdown_matches_docs)
  "$m" rules --markdown | cmp - "$src/docs/rules.md" ||
    fail "docs/rules.md is not what mococheck rules --markdown writes: regenerate it"
  ;;

*)
  echo "unknown test $test_name" >&2
  exit 1
  ;;
esac
cleanup
exit 0
