#!/usr/bin/env python3
"""tools/compare-verdicts on made-up reports: the same verdicts exit 0, a
changed verdict, a rule only one side judged and a device field that differs
each exit 1 and are named, and every report that cannot be read (missing, a
directory, a FIFO, not JSON, not a mococheck report, a rule twice, another
protocol) exits 2 with a message naming the file.

  compare_verdicts_test.py            (run from anywhere; needs python3 only)
"""

import json
import os
import subprocess
import sys
import tempfile
import unittest

TOOL = os.path.join(os.path.dirname(os.path.abspath(__file__)), "compare-verdicts")


def report(rules, protocol="dmc", device=None):
    return {
        "tool": "mococheck",
        "protocol": protocol,
        "target": "pty:/tmp/x",
        "device": device if device is not None else {"name": "dmc-lite", "motor_count": 8},
        "rules": [{"id": i, "level": lvl, "status": st, "cases_failed": cf, "cases_passed": 1}
                  for (i, lvl, st, cf) in rules],
    }


BASE = [("DMC-HI-001", "MUST", "pass", 0), ("DMC-ERR-006", "SHOULD", "note", 1),
        ("DMC-DMX-001", "MUST", "n/a", 0)]


class CompareVerdicts(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()

    def tearDown(self):
        self.dir.cleanup()

    def write(self, name, content):
        path = os.path.join(self.dir.name, name)
        with open(path, "w", encoding="utf-8") as f:
            f.write(content if isinstance(content, str) else json.dumps(content))
        return path

    def run_tool(self, *args):
        p = subprocess.run([sys.executable, TOOL, *args], capture_output=True, text=True,
                           timeout=60)
        return p.returncode, p.stdout, p.stderr

    def test_same_verdicts_exit_0(self):
        a = self.write("a.json", report(BASE))
        b = self.write("b.json", report(list(reversed(BASE))))
        rc, out, _ = self.run_tool(a, b)
        self.assertEqual(rc, 0, out)
        self.assertIn("same verdict on all 3 rules", out)

    def test_a_changed_verdict_is_named_with_both_sides(self):
        a = self.write("a.json", report(BASE))
        changed = list(BASE)
        changed[1] = ("DMC-ERR-006", "SHOULD", "pass", 0)
        b = self.write("b.json", report(changed))
        rc, out, _ = self.run_tool(a, b, "--labels", "real", "profile")
        self.assertEqual(rc, 1, out)
        line = [l for l in out.splitlines() if l.startswith("DMC-ERR-006")]
        self.assertEqual(len(line), 1, out)
        self.assertIn("real: note (1 case)", line[0])
        self.assertIn("profile: pass", line[0])
        self.assertIn("1 of 3 rules differ", out)
        self.assertNotIn("DMC-HI-001", out)

    def test_a_rule_one_side_lacks_and_a_device_field_differ(self):
        a = self.write("a.json", report(BASE))
        b = self.write("b.json", report(BASE[:2], device={"name": "dmc-lite", "motor_count": 16}))
        rc, out, _ = self.run_tool(a, b)
        self.assertEqual(rc, 1, out)
        self.assertIn("DMC-DMX-001", out)
        self.assertIn("(not in the report)", out)
        self.assertIn("device motor_count: A 8  B 16", out)

    def test_unreadable_reports_exit_2_naming_the_file(self):
        good = self.write("good.json", report(BASE))
        fifo = os.path.join(self.dir.name, "fifo")
        os.mkfifo(fifo)
        cases = {
            "missing": os.path.join(self.dir.name, "nope.json"),
            "directory": self.dir.name,
            "fifo": fifo,
            "not json": self.write("text.json", "PASS\n"),
            "empty": self.write("empty.json", ""),
            "not a report": self.write("other.json", {"rules": []}),
            "rule twice": self.write("twice.json", report(BASE + [BASE[0]])),
            "rule without status": self.write("nostatus.json",
                                              {"tool": "mococheck", "rules": [{"id": "X"}]}),
        }
        for what, path in cases.items():
            with self.subTest(what):
                rc, out, err = self.run_tool(good, path)
                self.assertEqual(rc, 2, what + ": " + out + err)
                self.assertIn(path, err)

    def test_reports_of_two_protocols_are_refused(self):
        a = self.write("a.json", report(BASE))
        b = self.write("b.json", report(BASE, protocol="dfmoco"))
        rc, _, err = self.run_tool(a, b)
        self.assertEqual(rc, 2)
        self.assertIn("one protocol", err)

    def test_bad_arguments_exit_2(self):
        a = self.write("a.json", report(BASE))
        for args in ([a], [a, a, a], [a, a, "--labels", "x"], [a, "--frobnicate"]):
            with self.subTest(args=args):
                rc, _, err = self.run_tool(*args)
                self.assertEqual(rc, 2)
                self.assertIn("usage", err)


if __name__ == "__main__":
    unittest.main()
