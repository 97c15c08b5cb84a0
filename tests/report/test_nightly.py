#!/usr/bin/python3
"""harness/scripts/nightly.sh on short horizons (docs/report.md, "The nightly job"). ctest:
report.nightly (label report).

  - a night of three exp1 runs (-j 1, cut at 3 s) stopped by SIGTERM after the first
    run: exit code 143, the finished run kept, the interrupted one marked "interrupted", no
    report yet;
  - the same command again resumes: the finished run is not redone (its summary is the same
    file), the others run, the comparisons, the report and one history record are written,
    the exit code follows the runs' verdicts;
  - a third time: nothing to run, the history still holds one record for the night;
  - a directory of another commit is refused (exit code 2), as is a bad configuration.
Usage: test_nightly.py --build-dir BUILD --work DIR
"""
import json
import os
import shutil
import signal
import subprocess
import sys
import time
import unittest

import lexdyn.history
import suite_options

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
NIGHTLY = os.path.join(ROOT, "harness", "scripts", "nightly.sh")
ARGS = None
IDS = ["exp1.bfgs", "exp1.ah", "exp1.wls"]


def expected_exit_code(out):
    """The rule of nightly.sh: 3 a run stopped early, 1 a check or comparison failed, else 0."""
    stopped = failed = False
    for rid in IDS:
        with open(os.path.join(out, rid, "summary.json")) as f:
            s = json.load(f)
        stopped |= s["status"] != "completed"
        failed |= any(not c["passed"] for c in s["checks"])
    with open(os.path.join(out, "compare", "exp1.json")) as f:
        failed |= any(not c["passed"] for c in json.load(f)["checks"])
    return 3 if stopped else (1 if failed else 0)


class Nightly(unittest.TestCase):
    def setUp(self):
        self.work = os.path.abspath(ARGS.work)
        shutil.rmtree(self.work, ignore_errors=True)
        os.makedirs(self.work)
        self.out = os.path.join(self.work, "night")
        self.history = os.path.join(self.work, "history.jsonl")
        # One small real sweep (two points of the point mass) instead of the nightly's own list.
        self.config = os.path.join(self.work, "nightly-test.yaml")
        with open(self.config, "w") as f:
            f.write("format: lexdyn-nightly/1\nsweeps:\n  - {file: cases/sweeps/pointmass-damping.yaml, points: 2}\n")

    def cmd(self, *extra):
        if "--config" not in extra:
            extra = ("--config", self.config) + extra
        return ["bash", NIGHTLY, "--out", self.out, "--history", self.history, "--build-dir", ARGS.build_dir,
                "--no-build", "--no-ctest", "-j", "1", "--only", ",".join(IDS), "--duration", "3", *extra]

    def test_interrupt_resume_and_rerun(self):
        # 1. Interrupted after the first run finished.
        p = subprocess.Popen(self.cmd(), stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
        lines = []
        deadline = time.time() + 300
        for line in p.stderr:
            lines.append(line)
            if "done  exp1.bfgs" in line:
                break
            self.assertLess(time.time(), deadline, "".join(lines))
        # Let the second run start, then stop the night.
        while not os.path.isfile(os.path.join(self.out, "exp1.ah", "log.txt")):
            time.sleep(0.05)
            self.assertLess(time.time(), deadline)
        p.send_signal(signal.SIGTERM)
        rest = p.stderr.read()
        p.stderr.close()
        code = p.wait(timeout=120)
        log = "".join(lines) + rest
        self.assertEqual(code, 143, log)
        self.assertIn("interrupted", rest)
        with open(os.path.join(self.out, "exp1.bfgs", "summary.json")) as f:
            self.assertEqual(json.load(f)["status"], "completed")
        ah = os.path.join(self.out, "exp1.ah", "summary.json")
        if os.path.isfile(ah):  # the harness had started: it stops after its tick, keeping its trace
            with open(ah) as f:
                self.assertEqual(json.load(f)["status"], "interrupted")
        self.assertFalse(os.path.exists(os.path.join(self.out, "exp1.wls", "summary.json")))
        self.assertFalse(os.path.exists(os.path.join(self.out, "report", "index.html")))
        self.assertFalse(os.path.exists(self.history))
        bfgs_stat = os.stat(os.path.join(self.out, "exp1.bfgs", "summary.json"))

        # 2. Resumed.
        r = subprocess.run(self.cmd(), capture_output=True, text=True, timeout=600)
        self.assertIn("resuming the night", r.stderr)
        self.assertIn("3 in all, 1 done earlier, 2 to run", r.stderr)
        self.assertNotIn("start exp1.bfgs", r.stderr)
        self.assertIn("start exp1.ah", r.stderr)
        self.assertRegex(r.stderr, r"done  exp1\.wls \(3/3\): completed")
        self.assertEqual(os.stat(os.path.join(self.out, "exp1.bfgs", "summary.json")).st_mtime_ns, bfgs_stat.st_mtime_ns)
        for rid in IDS:
            with open(os.path.join(self.out, rid, "summary.json")) as f:
                s = json.load(f)
            self.assertEqual(s["status"], "completed", rid)
            self.assertEqual(s["simulated_s"], 3.0, rid)
        self.assertTrue(os.path.isfile(os.path.join(self.out, "compare", "exp1.json")))
        self.assertTrue(os.path.isfile(os.path.join(self.out, "report", "index.html")), r.stderr)
        self.assertEqual(r.returncode, expected_exit_code(self.out), r.stderr)
        # The sweep ran (its failures go to a database beside the history).
        self.assertIn("sweep pointmass-damping", r.stderr)
        with open(os.path.join(self.out, "sweeps", "pointmass-damping", "summary.json")) as f:
            self.assertEqual(json.load(f)["completed"], 2)
        self.assertTrue(os.path.isdir(os.path.join(self.work, "sweep-failures")))
        with open(self.history) as f:
            recs = [json.loads(l) for l in f if l.strip()]
        self.assertEqual(len(recs), 1)
        with open(os.path.join(self.out, "nightly.json")) as f:
            meta = json.load(f)
        self.assertEqual(recs[0]["night"], meta["night"])
        self.assertEqual(sorted(recs[0]["runs"]), sorted(IDS))
        self.assertEqual(recs[0]["runs"]["exp1.bfgs"]["error_tasks"], ["right_hand", "left_hand"])

        # 3. Nothing left to run; the night's record is replaced, not added.
        r = subprocess.run(self.cmd(), capture_output=True, text=True, timeout=600)
        self.assertIn("3 in all, 3 done earlier, 0 to run", r.stderr)
        with open(self.history) as f:
            self.assertEqual(len([l for l in f if l.strip()]), 1)

    def test_another_commit_and_bad_configuration_are_refused(self):
        os.makedirs(self.out)
        lexdyn.history.write_night(os.path.join(self.out, "nightly.json"), lexdyn.history.night_info("0" * 40))
        r = subprocess.run(self.cmd(), capture_output=True, text=True, timeout=120)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("holds a night of commit " + "0" * 40, r.stderr)
        # A nightly.json that is no night's record is refused by name, not resumed.
        with open(os.path.join(self.out, "nightly.json"), "w") as f:
            json.dump({"format": "lexdyn-night/7", "night": "x", "commit": "0" * 40}, f)
        r = subprocess.run(self.cmd(), capture_output=True, text=True, timeout=120)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("nightly.json: format: expected 'lexdyn-night/1', found 'lexdyn-night/7'", r.stderr)
        cfg = os.path.join(self.work, "nightly.yaml")
        with open(cfg, "w") as f:
            f.write("format: lexdyn-nightly/1\nsweeps:\n  - {file: cases/sweeps/a.yaml, points: many}\n")
        r = subprocess.run(self.cmd("--config", cfg), capture_output=True, text=True, timeout=120)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn(f"{cfg}: sweeps[0].points: expected a positive integer, found 'many'", r.stderr)
        r = subprocess.run(self.cmd("-j", "0"), capture_output=True, text=True, timeout=120)
        self.assertEqual(r.returncode, 2)
        self.assertIn("-j: expected a positive integer, found '0'", r.stderr)


if __name__ == "__main__":
    suite_options.main(sys.modules[__name__], "--build-dir", "--work")
