#!/bin/sh
# The pin rules on real AVR firmware under simavr (conformance/rules/pin_rules.cpp):
#   simavr_pins_cli_test.sh TEST MOCOCHECK WORKDIR SOURCE_DIR ELF
# own_firmware_passes: the own DFMoco firmware passes every DFM-PIN rule, each judged
#   (each fault variant failing its rule and no other: SimavrPinProofs), and
#   the certificate of that run replays to the same verdicts.
# vcd_read_by_sigrok: the --vcd file, read back by sigrok-cli -I vcd, holds as many
#   signed STEP pulses of motor 1 as the firmware's last `mp 1` reported.
set -u
test_name=$1
m=$2
work=$3/$test_name
src=$4
elf=$5
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 1
# shellcheck source=../../tools/cli_test_lib.sh
. "$src/tools/cli_test_lib.sh"
board=$src/fixtures/boards/own-dfmoco.json

# Prints "id status" for every DFM-PIN rule, then "failing: ids" of every failed rule.
pin_summary() {
  python3 -c '
import json, sys
r = json.load(open(sys.argv[1]))
for x in r["rules"]:
    if "-PIN-" in x["id"]:
        print(x["id"], x["status"])
print("failing:", " ".join(sorted(x["id"] for x in r["rules"] if x["status"] == "fail")))
' "$1"
}

case "$test_name" in
own_firmware_passes)
  # Run as `certify` (the options and exit code of `run`, the whole suite),
  # so the same run also proves that the good firmware's certificate
  # replays to its verdicts (docs/certificates.md).
  "$m" keygen --out k >/dev/null 2>&1 || fail "keygen"
  "$m" certify --target "simavr:$elf" --protocol dfmoco --board "$board" --driver a4988 -q \
    --key k --out cert.json --json run.json --html run.html >out.txt 2>err.txt
  rc=$?
  pin_summary run.json >pins.txt || fail "no JSON report"
  [ "$rc" = 0 ] || fail "exit $rc, not 0"
  [ "$(grep -c ' pass$' pins.txt)" = 7 ] || fail "not every DFM-PIN rule passed: $(cat pins.txt)"
  grep -q '^failing: $' pins.txt || fail "a rule failed: $(cat pins.txt)"
  expect_rc 0 "$m" verify cert.json --key k.pub --replay --firmware "$elf"
  grep -q "^replay: *same verdicts" out.txt || fail "the replay differs: $(cat out.txt)"
  ;;
vcd_read_by_sigrok)
  # No output over a file the run reads (refused before anything runs).
  cp "$elf" fw.elf && cp "$board" b.json
  expect_rc 2 "$m" run --target simavr:fw.elf --protocol dfmoco --board b.json --vcd fw.elf
  grep -q "is the --target's firmware" err.txt || fail "--vcd over the firmware: $(cat err.txt)"
  expect_rc 2 "$m" run --target simavr:fw.elf --protocol dfmoco --board b.json --json b.json
  grep -q "is the --board" err.txt || fail "--json over the board: $(cat err.txt)"
  cmp -s fw.elf "$elf" && cmp -s b.json "$board" || fail "an input was overwritten"
  # motor/move: motor 1 to 6000 steps and back to 0.
  expect_rc 0 "$m" run --target "simavr:$elf" --protocol dfmoco --board "$board" \
    --cases 'motor/move' -q --vcd run.vcd --json run.json
  [ -s run.vcd ] || fail "no VCD written"
  # sigrok reads the dump (1 ns timescale) at 1 MHz and writes its own VCD back.
  sigrok-cli -I vcd:downsample=1000 -i run.vcd -O vcd -o back.vcd >sigrok.txt 2>&1 ||
    fail "sigrok-cli could not read run.vcd"
  # Motor 1's signed STEP count (DIR high: +1) at the end, and its highest value.
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
print(c["last_positions"]["1"], c["position_range"]["1"][1])
' run.json)
  echo "sigrok: final, highest, rising edges: $steps; reported final, highest: $reported"
  set -- $steps
  [ "$1 $2" = "$reported" ] || fail "sigrok counts $steps (final, highest, edges); mp 1 said $reported"
  [ "$3" = 12000 ] || fail "sigrok counts $3 STEP pulses, not 12000 (6000 out, 6000 back)"
  ;;
# sigterm_mid_case: SIGTERM while a long case runs the firmware ends the run at
#   once (the case's waits end, not only the run between cases), with the
#   reports written and exit 2.
sigterm_mid_case)
  "$m" run --target "simavr:$elf" --protocol dfmoco --cases 'random/*' --steps 100000 \
    --json run.json --junit run.xml >out.txt 2>err.txt &
  check=$!
  pids="$pids $check"
  wait_for grep -q 'random/sequence' err.txt || fail "the case did not start"
  signal_and_wait TERM "$check"
  [ "$rc" = 2 ] || fail "exit $rc, not 2"
  grep -q '^result: INTERRUPTED' out.txt || fail "no INTERRUPTED verdict"
  grep -q '"interrupted_case": "random/sequence"' run.json || fail "the case is not named"
  grep -q '<error message="interrupted by signal' run.xml || fail "JUnit has no error"
  ;;
*)
  fail "unknown test $test_name"
  ;;
esac
exit 0
