#!/bin/sh
# The native target through the command line (docs/firmware-ci.md "Any board"):
#   native_cli_test.sh TEST MOCOCHECK BUILD_NATIVE WORKDIR SOURCE_DIR [FIRMWARE [GOOD]]
# esp32_certifies: the ESP32 DFMoco sketch (hw_timer, portMUX, BluetoothSerial),
#   built by mococheck-build-native, certifies over its Bluetooth port with every
#   DFM-PIN rule judged and passing; the certificate replays to its verdicts and
#   names the executable; the same sketch built by the CMake function
#   (moco_add_native_firmware SKETCH_DIR) gives the same verdicts.
# teensy_port_passes: the same sketch built for a Teensy 4.0 (IntervalTimer, the
#   protocol on USB Serial) passes the suite with every DFM-PIN rule judged; its
#   --vcd file reads back in sigrok-cli with the board's eight signals.
# fuzz_finds_and_replays (FIRMWARE: the DFMoco firmware with BUG_ZERO_RATE, GOOD:
#   without it): `fuzz --target native:` mutates the golden session, each run a
#   fresh process, and finds the division by zero as its own kind; the saved
#   finding replays to it, and the good firmware passes it.
# build_refuses_bad_input: a missing folder, an empty one, an unknown board, an
#   output that is a folder are refused with exit 2 naming the fix; a sketch
#   that does not compile exits 1 with the compiler's message at the .ino's own
#   line; an output path that is a symlink is replaced, never written through.
set -u
test_name=$1
m=$2
build=$3
work=$4/$test_name
src=$5
cmake_built=${6:-}
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 1
# shellcheck source=../../tools/cli_test_lib.sh
. "$src/tools/cli_test_lib.sh"

# Prints "id status" of every rule of a JSON report, sorted.
verdicts() {
  python3 -c '
import json, sys
for x in sorted(json.load(open(sys.argv[1]))["rules"], key=lambda x: x["id"]):
    print(x["id"], x["status"])
' "$1"
}

case "$test_name" in
esp32_certifies)
  expect_rc 0 "$build" "$src/fixtures/firmware/dfmoco_esp32" --board esp32 -o rig.native
  [ -x rig.native ] || fail "no executable written"
  "$m" keygen --out k >/dev/null 2>&1 || fail "keygen"
  board=$src/fixtures/boards/dfmoco-esp32.json
  "$m" certify --target native:rig.native@bluetooth --protocol dfmoco --board "$board" \
    --driver a4988 -q --key k --out cert.json --json run.json >out.txt 2>err.txt
  rc=$?
  [ "$rc" = 0 ] || fail "certify exit $rc, not 0"
  verdicts run.json >v.txt || fail "no JSON report"
  [ "$(grep -c 'DFM-PIN-00[1-7] pass$' v.txt)" = 7 ] || fail "not every pin rule passed: $(cat v.txt)"
  grep -q ' fail$' v.txt && fail "a rule failed: $(grep ' fail$' v.txt)"
  grep -q 'native:rig.native@bluetooth' run.json || fail "the report does not name the target"
  expect_rc 0 "$m" verify cert.json --key k.pub --replay --firmware rig.native
  grep -q "^replay: *same verdicts" out.txt || fail "the replay differs: $(cat out.txt)"
  if [ -n "$cmake_built" ]; then
    expect_rc 0 "$m" run --target "native:$cmake_built@bluetooth" --protocol dfmoco \
      --board "$board" --driver a4988 -q --json cmake.json
    verdicts cmake.json >c.txt
    cmp -s v.txt c.txt || fail "the CMake-built sketch judged otherwise: $(diff v.txt c.txt)"
  fi
  ;;
teensy_port_passes)
  expect_rc 0 "$build" "$src/fixtures/firmware/dfmoco_esp32" --board teensy40 -o rig.native
  expect_rc 0 "$m" run --target native:rig.native --protocol dfmoco \
    --board "$src/fixtures/boards/dfmoco-esp32.json" --driver a4988 -q --json run.json
  verdicts run.json >v.txt || fail "no JSON report"
  # The pins of one case as a VCD (1 ns timescale), read by sigrok at 1 MHz.
  expect_rc 0 "$m" run --target native:rig.native --protocol dfmoco --cases 'motor/move' \
    --board "$src/fixtures/boards/dfmoco-esp32.json" -q --vcd run.vcd
  sigrok-cli -I vcd:downsample=1000 -i run.vcd --show >sigrok.txt 2>&1 ||
    fail "sigrok-cli cannot read the VCD"
  [ "$(grep -c -- '- m[1-4]_\(step\|dir\): logic' sigrok.txt)" = 8 ] ||
    fail "the VCD lacks the board's signals: $(cat sigrok.txt)"
  [ "$(grep -c 'DFM-PIN-00[1-7] pass$' v.txt)" = 7 ] || fail "not every pin rule passed: $(cat v.txt)"
  grep -q 'teensy40' run.json || fail "the report does not name the board"
  ;;
fuzz_finds_and_replays)
  bug=$cmake_built
  good=$7
  expect_rc 1 "$m" fuzz "$src/fixtures/sessions/dfmoco-uno-workflow.jsonl" \
    --target "native:$bug" --seed 4 --runs 200 --max-failures 1 --crashes found
  grep -q '^FAIL \[division-by-zero\] the firmware stopped: the sketch stopped at a division by zero (SIGFPE)' \
    out.txt || fail "no division-by-zero finding"
  saved=$(sed -n 's/.*; saved: \(found\/mutant-[0-9-]*\.jsonl\)$/\1/p' out.txt | head -1)
  [ -s "$saved" ] || fail "no saved finding ($saved)"
  grep -q "^  rerun: mococheck replay $saved --target native:$bug" out.txt || fail "no rerun line"
  expect_rc 1 "$m" replay "$saved" --target "native:$bug"
  grep -q '^FAIL \[division-by-zero\]' out.txt || fail "the replay does not find it again"
  expect_rc 0 "$m" replay "$saved" --target "native:$good"
  grep -q '^result: PASS' out.txt || fail "the good firmware does not pass the finding's session"
  ;;
build_refuses_bad_input)
  expect_rc 2 "$build" no-such-folder --board esp32
  grep -q "is not a folder" err.txt || fail "missing folder: $(cat err.txt)"
  mkdir Empty
  expect_rc 2 "$build" Empty
  grep -q "holds no .ino" err.txt || fail "empty folder: $(cat err.txt)"
  mkdir Bad
  printf 'void setup() {}\nvoid loop() {\n  undeclared_thing();\n}\n' >Bad/Bad.ino
  expect_rc 2 "$build" Bad --board esp33
  grep -q 'the boards are: .*esp32.*uno' err.txt || fail "unknown board: $(cat err.txt)"
  mkdir out.native
  expect_rc 2 "$build" Bad -o out.native
  grep -q "is a folder" err.txt || fail "-o a folder: $(cat err.txt)"
  expect_rc 1 "$build" Bad --board uno -o bad.native
  grep -q "Bad.ino:3" err.txt || fail "the error is not at the .ino's line: $(cat err.txt)"
  [ -e bad.native ] && fail "a failed build left an executable"
  # A planted symlink at the output path is replaced; its target keeps its bytes.
  mkdir Good
  printf 'void setup() { Serial.begin(9600); }\nvoid loop() { tick(); }\nvoid tick() {}\n' \
    >Good/Good.ino
  echo keep >precious.txt
  ln -s precious.txt link.native
  expect_rc 0 "$build" Good -o link.native
  [ "$(cat precious.txt)" = keep ] || fail "the build wrote through the symlink"
  [ -L link.native ] && fail "the symlink is still there"
  [ -x link.native ] || fail "no executable at the link's path"
  # The executable says how to run it when started by hand.
  expect_rc 2 ./link.native
  grep -q "mococheck run --target native:" err.txt || fail "no hint when run by hand: $(cat err.txt)"
  ;;
*)
  fail "unknown test $test_name"
  ;;
esac
exit 0
