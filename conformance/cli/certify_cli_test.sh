#!/bin/sh
# `mococheck keygen`, `certify` and `verify` through the command line
# (docs/certificates.md):
#   certify_cli_test.sh TEST MOCOCHECK WORKDIR SOURCE_DIR [GOOD_ELF FAULT_ELF]
# keygen: a key pair with the private key at mode 0600; an existing file or a
#   planted symlink is never written through or over.
# in_process_MODEL: a certificate of the emulated device verifies with its
#   maker's key, `verify --replay` judges its traffic again to the same
#   verdicts, and each tampering (a verdict, one transcript byte, the
#   catalogue's or the firmware's digest, another key) fails naming it; the
#   replayed run's page, loaded in headless Chromium, shows what the
#   certificate holds (tools/report-dom-check).
# simavr: a build of our DFMoco firmware that loses steps, its pins watched:
#   the certificate replays to its verdicts, the DFM-PIN-001 failure
#   included, and --firmware tells its image from the good build's.
# usage: subsets are refused, a bad key or a file that is not a certificate
#   is named, and nothing is written by a refused command.
set -u
test_name=$1
m=$2
work=$3/$test_name
src=$4
good=${5:-}
fault=${6:-}
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 1
# shellcheck source=../../tools/cli_test_lib.sh
. "$src/tools/cli_test_lib.sh"

# tamper CERT OUT PYTHON: OUT is CERT with the change PYTHON makes to `c`.
tamper() {
  python3 - "$1" "$2" "$3" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))
exec(sys.argv[3])
json.dump(c, open(sys.argv[2], "w"))
PY
}

# expect_not_verified CERT WORDS: verify fails (exit 1) naming WORDS.
expect_not_verified() {
  expect_rc 1 "$m" verify "$1" --key k.pub
  grep -q "^result: NOT VERIFIED" out.txt || fail "$1: no NOT VERIFIED"
  grep -q "$2" out.txt || fail "$1: the problem is not named ($2): $(cat out.txt)"
}

case "$test_name" in
keygen)
  expect_rc 0 "$m" keygen --out k
  [ "$(stat -c %a k)" = 600 ] || fail "the private key is mode $(stat -c %a k), not 600"
  grep -q "BEGIN PRIVATE KEY" k || fail "no PEM private key"
  grep -q "BEGIN PUBLIC KEY" k.pub || fail "no PEM public key"
  grep -q "^key id: *[0-9a-f]\{16\}$" out.txt || fail "no key id: $(cat out.txt)"
  cp k k.before
  expect_rc 2 "$m" keygen --out k
  grep -q "never overwrites" err.txt || fail "no refusal for an existing key"
  cmp -s k k.before || fail "the existing key was changed"
  ln -s "$work/planted" trap
  expect_rc 2 "$m" keygen --out trap
  [ ! -e planted ] || fail "keygen wrote through a planted symlink"
  ls ./*.partial-* >/dev/null 2>&1 && fail "a temporary file was left"
  mkdir -p nodir-parent && expect_rc 2 "$m" keygen --out nodir/k
  ;;

in_process_dmc16 | in_process_dfmoco | in_process_stackshot3x)
  model=${test_name#in_process_}
  "$m" keygen --out k >/dev/null 2>&1 || fail "keygen"
  expect_rc 0 "$m" certify --target "in-process:$model" --key k --out cert.json -q --html run.html
  grep -q "^certificate: cert.json (.*sealed by key [0-9a-f]\{16\})" out.txt ||
    fail "no certificate line: $(cat out.txt)"
  size=$(stat -c %s cert.json)
  [ "$size" -lt 8000000 ] || fail "the certificate is $size bytes"
  expect_rc 0 "$m" verify cert.json --key k.pub --replay
  grep -q "^result: VERIFIED" out.txt || fail "not verified: $(cat out.txt)"
  grep -q "^replay: *same verdicts" out.txt || fail "the replay differs: $(cat out.txt)"
  # The badge, the paragraph and the page, each derived from the certificate.
  expect_rc 0 "$m" verify cert.json --key k.pub --replay --badge badge.svg --summary --html c.html
  python3 -c 'import sys, xml.dom.minidom as m; m.parse(sys.argv[1])' badge.svg ||
    fail "the badge is not well-formed XML"
  grep -q "mococheck $(sed -n 's/.*"protocol": "\([a-z]*\)".*/\1/p' cert.json | head -1)" badge.svg ||
    fail "the badge does not name the protocol"
  grep -q "certified [0-9]*/[0-9]* MUST" badge.svg || fail "the badge gives no MUST count"
  grep -q "passed the mococheck .* conformance suite on 20[0-9-]*: [0-9]* MUST rules passed and 0 failed" out.txt ||
    fail "no summary paragraph: $(cat out.txt)"
  # The pages as headless Chromium builds them, certify's and verify's, hold
  # what the certificate holds; the same page with one rule's row taken out
  # does not.
  "$src/tools/report-dom-check" run.html cert.json --certificate cert.json cert.json --sealed \
    >dom.txt 2>&1 || fail "certify's page in Chromium: $(cat dom.txt)"
  "$src/tools/report-dom-check" c.html cert.json --certificate cert.json cert.json >dom.txt 2>&1 ||
    fail "verify's page in Chromium: $(cat dom.txt)"
  python3 - c.html cut.html <<'PY'
import re, sys
page = open(sys.argv[1]).read()
cut = re.sub(r'<tr><td class="id">[^\n]*</tr>\n', "", page, count=1)
assert cut != page, "no rule row to take out"
open(sys.argv[2], "w").write(cut)
PY
  "$src/tools/report-dom-check" cut.html cert.json >dom.txt 2>&1 &&
    fail "a page missing a rule's row passes the check"
  grep -q "has no row in the Rules table" dom.txt || fail "the missing row is not named: $(cat dom.txt)"
  expect_rc 2 "$m" verify cert.json --key k.pub --html c2.html
  grep -q "needs --replay" err.txt || fail "--html without --replay is not refused"
  # The suite run again against the same model gives the same verdicts; a
  # device of another protocol is refused before anything runs.
  expect_rc 0 "$m" verify cert.json --key k.pub --target "in-process:$model"
  grep -q "^device: *same verdicts" out.txt || fail "another run differs: $(cat out.txt)"
  other=dfmoco
  [ "$model" = dfmoco ] && other=dmc16
  expect_rc 2 "$m" verify cert.json --key k.pub --target "in-process:$other"
  # Each change is named.
  tamper cert.json verdict.json '
for r in c["report"]["rules"]:
    if r["status"] == "pass":
        r["status"] = "fail"; break'
  expect_not_verified verdict.json "the verdict of rule .* was changed"
  tamper cert.json transcript.json '
d = c["transcript"]["data"]; i = len(d) // 2
c["transcript"]["data"] = d[:i] + ("B" if d[i] == "A" else "A") + d[i+1:]'
  expect_not_verified transcript.json 'the transcript ("transcript") was changed'
  tamper cert.json catalogue.json 'c["catalogue"]["sha256"] = "0" * 64'
  expect_not_verified catalogue.json "made with another rule catalogue"
  tamper cert.json firmware.json 'c["firmware"] = {"file": "x.elf", "sha256": "1" * 64}'
  expect_not_verified firmware.json "the firmware image's digest (\"firmware\") was changed"
  "$m" keygen --out other >/dev/null 2>&1 || fail "keygen"
  expect_rc 1 "$m" verify cert.json --key other.pub
  grep -q "not by the key given" out.txt || fail "another key is not named"
  ;;

simavr)
  # Pins watched, the firmware build that loses steps: its DFM-PIN-001
  # failure replays from the certificate (the good build's certificate
  # replays in simavr_pins_cli_test.sh own_firmware_passes).
  "$m" keygen --out k >/dev/null 2>&1 || fail "keygen"
  board="$src/fixtures/boards/own-dfmoco.json"
  expect_rc 1 "$m" certify --target "simavr:$fault" --protocol dfmoco --board "$board" \
    --driver a4988 --key k --out bad.json -q --json run.json --html run.html
  [ -s bad.json ] || fail "a failing run got no certificate"
  # The fault fails DFM-PIN-001 and no other rule (as `run` would report it).
  failing=$(python3 -c 'import json, sys
print(" ".join(sorted(r["id"] for r in json.load(open(sys.argv[1]))["rules"] if r["status"] == "fail")))' run.json)
  [ "$failing" = DFM-PIN-001 ] || fail "failing: '$failing', not exactly DFM-PIN-001"
  sealed=$(python3 -c 'import json, sys
print(" ".join(sorted(r["id"] for r in json.load(open(sys.argv[1]))["report"]["rules"] if r["status"] == "fail")))' bad.json)
  [ "$sealed" = DFM-PIN-001 ] || fail "the certificate says '$sealed' failed"
  expect_rc 0 "$m" verify bad.json --key k.pub --replay --firmware "$fault"
  grep -q "^verdict: *FAIL" out.txt || fail "the sealed verdict is not FAIL"
  grep -q "^replay: *same verdicts" out.txt || fail "the replay differs: $(cat out.txt)"
  grep -q "^firmware: *$(basename "$fault") sha256 $(sha256sum "$fault" | cut -c1-64)" out.txt ||
    fail "the firmware digest is not shown: $(cat out.txt)"
  # Both pages of the failing run, the run's own and the replayed
  # certificate's, as headless Chromium builds them: the failure shown open,
  # its rule linked to it.
  "$src/tools/report-dom-check" run.html run.json >dom.txt 2>&1 ||
    fail "the run's page in Chromium: $(cat dom.txt)"
  expect_rc 0 "$m" verify bad.json --key k.pub --replay --html bad.html
  "$src/tools/report-dom-check" bad.html bad.json --certificate bad.json bad.json >dom.txt 2>&1 ||
    fail "the certificate's page in Chromium: $(cat dom.txt)"
  grep -q '<a href="#DFM-PIN-001">' bad.html || fail "the failing rule is not linked to its finding"
  expect_rc 1 "$m" verify bad.json --key k.pub --firmware "$good"
  grep -q "is not the certified image" out.txt || fail "another image is not named"
  ;;

usage)
  "$m" keygen --out k >/dev/null 2>&1 || fail "keygen"
  expect_rc 2 "$m" certify --target in-process:dfmoco --key k --out c.json --cases 'connect/*'
  grep -q "cases" err.txt || fail "--cases is not refused by name"
  expect_rc 2 "$m" certify --target in-process:dfmoco --key k.pub --out c.json
  grep -q "not an Ed25519 private key" err.txt || fail "a public key given as --key"
  expect_rc 2 "$m" certify --target in-process:dfmoco --key k --out k
  grep -q "destroy the key" err.txt || fail "--out over the key"
  # No report may be written over a file the run reads: the key, the
  # profile, the firmware.
  cp k k.before
  for report in --json --junit --html; do
    expect_rc 2 "$m" certify --target in-process:dfmoco --key k --out c.json "$report" k
    grep -q "is the --key; writing it would destroy the key" err.txt ||
      fail "$report over the key: $(cat err.txt)"
  done
  cmp -s k k.before || fail "the key was overwritten"
  cp "$src/fixtures/profiles/dfmoco-uno.json" p.json
  expect_rc 2 "$m" certify --target in-process:dfmoco --profile p.json --key k --out c.json --json p.json
  grep -q "is the --profile" err.txt || fail "--json over the profile: $(cat err.txt)"
  [ ! -e c.json ] || fail "a certificate was written by a refused command"
  printf 'not json' >bad.json
  expect_rc 2 "$m" verify bad.json --key k.pub
  grep -q "is not JSON" err.txt || fail "a file that is not JSON"
  expect_rc 2 "$m" verify missing.json --key k.pub
  expect_rc 2 "$m" verify . --key k.pub
  expect_rc 2 "$m" verify bad.json --key k
  grep -q "not an Ed25519 public key" err.txt || fail "a private key given to verify"
  : >empty.json
  expect_rc 2 "$m" verify empty.json --key k.pub
  echo '{}' >nothing.json
  expect_rc 1 "$m" verify nothing.json --key k.pub
  grep -q "not a mococheck certificate" out.txt || fail "{} is called a certificate"
  # Fields of the wrong type are a problem, never a crash.
  echo '[]' >array.json
  expect_rc 1 "$m" verify array.json --key k.pub --firmware array.json
  grep -q "^result: NOT VERIFIED" out.txt || fail "[] is not refused"
  echo '{"format": "mococheck-certificate/1", "device": "x", "seal": 5}' >types.json
  expect_rc 1 "$m" verify types.json --key k.pub --replay
  grep -q "^result: NOT VERIFIED" out.txt || fail "a certificate of wrong types is not refused"
  ;;
*)
  fail "unknown test $test_name"
  ;;
esac
exit 0
