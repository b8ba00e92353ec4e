#!/usr/bin/env python3
"""tools/rule-proofs check against stand-in binaries: a catalogue of three
rules (two MUST, one NOTE) and one test binary whose tests log what they catch
only when told to. Checks what the CTest proof log (--log) may and may not
stand in for:

  - a fresh log holding every table line: sound, no proving test run again;
  - a log lacking a line: that test alone is run, and when it no longer
    catches its rule the check fails naming it;
  - a log older than the binaries (an earlier build's), a log that is a
    symbolic link, or a directory: ignored, every proving test run;
  - a MUST rule with no table line fails whatever the log says.

  rule_proofs_test.py            (run from anywhere; needs python3 only)
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

TOOL = os.path.join(os.path.dirname(os.path.abspath(__file__)), "rule-proofs")

CATALOGUE = [
    {"id": "DMC-A-001", "level": "MUST"},
    {"id": "DMC-A-002", "level": "MUST"},
    {"id": "DMC-A-003", "level": "NOTE"},
]

# The stand-in test binary: lists Proofs.CatchesA1 and Proofs.CatchesA2; a test
# run appends its line to MOCO_PROOF_LOG unless BROKEN names it, and every run
# is counted in RUNS (one line per test run).
FAKE_TEST = r"""#!/usr/bin/env python3
import os, sys
tests = {"Proofs.CatchesA1": "DMC-A-001", "Proofs.CatchesA2": "DMC-A-002"}
if "--gtest_list_tests" in sys.argv:
    print("Proofs.")
    for t in tests:
        print("  " + t.split(".")[1])
    sys.exit(0)
chosen = [a for a in sys.argv[1:] if a.startswith("--gtest_filter=")]
names = chosen[0].split("=", 1)[1].split(":") if chosen else list(tests)
broken = os.environ.get("BROKEN", "")
for n in names:
    with open(os.environ["RUNS"], "a") as f:
        f.write(n + "\n")
    if n != broken and os.environ.get("MOCO_PROOF_LOG"):
        with open(os.environ["MOCO_PROOF_LOG"], "a") as f:
            f.write(n + "\t" + tests[n] + "\n")
"""


class RuleProofsCheck(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="rule-proofs-test-")
        # The tool reads its tables from the tree it lives in: give it a tree
        # of its own (tools/rule-proofs and conformance/rules/proofs/).
        self.root = os.path.join(self.dir, "tree")
        os.makedirs(os.path.join(self.root, "tools"))
        self.proofs = os.path.join(self.root, "conformance", "rules", "proofs")
        os.makedirs(self.proofs)
        shutil.copy(TOOL, os.path.join(self.root, "tools", "rule-proofs"))
        self.write_tables(["DMC-A-001\tProofs.CatchesA1", "DMC-A-002\tProofs.CatchesA2"])
        self.mococheck = self.script("mococheck", "#!/bin/sh\necho '%s'\n" % json.dumps(CATALOGUE))
        self.binary = self.script("proofs_test", FAKE_TEST)
        self.runs = os.path.join(self.dir, "runs")
        self.log = os.path.join(self.dir, "rule-proofs.log")

    def tearDown(self):
        shutil.rmtree(self.dir)

    def script(self, name, text):
        path = os.path.join(self.dir, name)
        with open(path, "w") as f:
            f.write(text)
        os.chmod(path, 0o755)
        return path

    def write_tables(self, dmc_lines):
        for name in ("dmc", "dfmoco", "stackshot"):
            lines = dmc_lines if name == "dmc" else []
            with open(os.path.join(self.proofs, name + ".tsv"), "w") as f:
                f.write("# table\n" + "".join(l + "\n" for l in lines))

    def write_log(self, lines):
        with open(self.log, "w") as f:
            f.write("".join(l + "\n" for l in lines))

    def check(self, broken="", extra=(), binary=None):
        env = dict(os.environ, RUNS=self.runs, BROKEN=broken)
        env.pop("MOCO_PROOF_LOG", None)
        p = subprocess.run([sys.executable, os.path.join(self.root, "tools", "rule-proofs"),
                            "check", "--log", self.log, *extra, self.mococheck,
                            binary or self.binary],
                           capture_output=True, text=True, env=env)
        runs = []
        if os.path.exists(self.runs):
            with open(self.runs) as f:
                runs = f.read().split()
        return p.returncode, p.stdout + p.stderr, runs

    def test_a_fresh_log_with_every_line_is_sound_and_runs_nothing(self):
        self.write_log(["Proofs.CatchesA1\tDMC-A-001", "Proofs.CatchesA2\tDMC-A-002"])
        rc, out, runs = self.check()
        self.assertEqual(rc, 0, out)
        self.assertEqual(runs, [], out)
        self.assertIn("2 proof(s) read from the CTest run's log, 0 test(s) run here", out)

    def test_a_line_missing_from_the_log_runs_that_test_alone(self):
        self.write_log(["Proofs.CatchesA1\tDMC-A-001"])
        rc, out, runs = self.check()
        self.assertEqual(rc, 0, out)
        self.assertEqual(runs, ["Proofs.CatchesA2"], out)

    def test_a_test_that_no_longer_catches_its_rule_fails_the_check(self):
        self.write_log(["Proofs.CatchesA1\tDMC-A-001"])
        rc, out, runs = self.check(broken="Proofs.CatchesA2")
        self.assertEqual(rc, 1, out)
        self.assertIn("Proofs.CatchesA2 no longer shows DMC-A-002 failing", out)

    def test_a_log_older_than_the_binaries_is_ignored(self):
        self.write_log(["Proofs.CatchesA1\tDMC-A-001", "Proofs.CatchesA2\tDMC-A-002"])
        old = time.time() - 3600
        os.utime(self.log, (old, old))
        rc, out, runs = self.check(broken="Proofs.CatchesA1")
        self.assertEqual(rc, 1, out)
        self.assertIn("older than the test binaries: ignored", out)
        self.assertEqual(sorted(runs), ["Proofs.CatchesA1", "Proofs.CatchesA2"], out)
        self.assertIn("Proofs.CatchesA1 no longer shows DMC-A-001 failing", out)

    def test_a_log_that_is_a_symlink_or_a_directory_is_ignored(self):
        target = os.path.join(self.dir, "elsewhere.log")
        with open(target, "w") as f:
            f.write("Proofs.CatchesA1\tDMC-A-001\nProofs.CatchesA2\tDMC-A-002\n")
        os.symlink(target, self.log)
        rc, out, runs = self.check(broken="Proofs.CatchesA2")
        self.assertEqual(rc, 1, out)
        self.assertIn("is not a regular file: ignored", out)
        os.remove(self.log)
        os.mkdir(self.log)
        rc, out, runs = self.check()
        self.assertEqual(rc, 0, out)
        self.assertIn("is not a regular file: ignored", out)

    def test_no_log_runs_every_proving_test(self):
        rc, out, runs = self.check()
        self.assertEqual(rc, 0, out)
        self.assertIn("no proof log at", out)
        self.assertEqual(sorted(runs), ["Proofs.CatchesA1", "Proofs.CatchesA2"])

    def test_a_must_rule_without_a_table_line_fails_whatever_the_log_says(self):
        self.write_tables(["DMC-A-001\tProofs.CatchesA1"])
        self.write_log(["Proofs.CatchesA1\tDMC-A-001", "Proofs.CatchesA2\tDMC-A-002"])
        rc, out, runs = self.check()
        self.assertEqual(rc, 1, out)
        self.assertIn("DMC-A-002 (MUST) has no proving test", out)

    def test_a_suite_named_unbuilt_that_is_built_is_refused(self):
        # Its broken proof would otherwise count as proven.
        self.write_log(["Proofs.CatchesA1\tDMC-A-001"])
        rc, out, runs = self.check(broken="Proofs.CatchesA2", extra=("--unbuilt", "Proofs"))
        self.assertEqual(rc, 2, out)
        self.assertIn("--unbuilt Proofs: the suite is in the binaries given", out)
        self.assertEqual(runs, [], out)

    def test_a_binary_that_cannot_list_its_tests_is_a_usage_error(self):
        bad = self.script("crashing_test", "#!/bin/sh\necho 'cannot load' >&2\nexit 3\n")
        rc, out, runs = self.check(binary=bad)
        self.assertEqual(rc, 2, out)
        self.assertIn("--gtest_list_tests failed (exit 3: cannot load)", out)
        self.assertNotIn("Traceback", out)


if __name__ == "__main__":
    unittest.main()
