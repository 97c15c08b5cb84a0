#!/usr/bin/python3
"""The nightly report under faults (harness/scripts/report.py, nightly.sh; docs/report.md,
"Locks", "Building and swapping", "History and trend"). ctest: faults.report (label faults).

The runs are real: the point mass (cases/pointmass-damping.yaml) with GN and WLS, 1 s each, by
the harness given with --harness; each "night" is a copy of them with its own nightly.json (as
nightly.sh writes it). The history files are the report's own, damaged afterwards; a damaged
summary is a real one with a figure replaced by NaN.

  - a full disk (a small tmpfs; where mounting is not permitted, a file-size limit): the
    rebuilt report fails with exit code 3 and one line naming the file and the reason, the
    previous report (index.html, figures/, replay/, every byte) and the history are left as they
    were, no temporary file or folder is left; once there is room the report is rebuilt;
  - a read-only file system: exit code 3, "Read-only file system" (tmpfs only);
  - two report.py on one --out: the second exits 2 at once naming the first's pid and command,
    the first completes; nightly.sh on a locked folder likewise;
  - a lock file of a dead process (and its staging folder) is taken over, the same file;
  - a bad --out (a file, a path through a file) exits 2 with one line;
  - a history with a cut last line, a garbage line, a record of another format version, a
    record whose runs is a list: the report is built, the warning is on the page and printed,
    the night is appended, the line kept; --strict-history refuses (exit 2 naming file, line
    and field) and changes nothing;
  - nights appended out of order are kept in date order, a rebuilt older night replaces its
    record in place, and "since last night" is the latest night dated before;
  - NaN and Infinity in a summary and in history figures are shown as "not a number
    (damaged)", never as nan, never a point of a trend, and written as null.
Usage: test_report_faults.py --harness PATH --work DIR
"""
import datetime
import hashlib
import json
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import time
import unittest

import lexdyn.history
import suite_options  # tests/report (PYTHONPATH: tests/faults/CMakeLists.txt)

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))

REPORT = os.path.join(ROOT, "harness", "scripts", "report.py")
NIGHTLY = os.path.join(ROOT, "harness", "scripts", "nightly.sh")
PY = "/usr/bin/python3"
DAMAGED = "not a number (damaged)"
ARGS = None
RUNS = [("pointmass-damping.gn", "gn"), ("pointmass-damping.wls", "wls")]


def report(*args, limit_bytes=None, timeout=300):
    """report.py ARGS; with LIMIT_BYTES, under a file-size limit (SIGXFSZ ignored, as Python
    does: a write beyond it fails with "File too large")."""
    def limited():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit_bytes, limit_bytes))
    return subprocess.run([PY, REPORT, *args], capture_output=True, text=True, timeout=timeout,
                          preexec_fn=limited if limit_bytes else None)


def tree(path):
    """{relative path: sha256} of every file under PATH but its lock file."""
    out = {}
    for d, _, names in os.walk(path):
        for n in names:
            p = os.path.join(d, n)
            rel = os.path.relpath(p, path)
            if rel == ".lexdyn.lock":
                continue
            with open(p, "rb") as f:
                out[rel] = hashlib.sha256(f.read()).hexdigest()
    return out


def leftovers(path):
    """Temporary files and folders of a report left under PATH."""
    out = []
    for d, dirs, names in os.walk(path):
        for n in dirs + names:
            if ".partial" in n or n.startswith((".staging-", ".old-")):
                out.append(os.path.relpath(os.path.join(d, n), path))
    return out


def read(path):
    with open(path) as f:
        return f.read()


def error_lines(stderr):
    return [l for l in stderr.splitlines() if l.strip()]


def dead_pid():
    p = subprocess.Popen(["true"])
    p.wait()
    return p.pid


def cells(page):
    """The text of every table cell of a page."""
    return [re.sub(r"<[^>]+>", "", c).strip() for c in re.findall(r"<td[^>]*>(.*?)</td>", page, re.S)]


class ReportFaults(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.work = os.path.abspath(ARGS.work)
        cls.unmount_all()
        shutil.rmtree(cls.work, ignore_errors=True)
        os.makedirs(cls.work)
        cls.runs = os.path.join(cls.work, "runs")
        for rid, method in RUNS:
            cmd = [ARGS.harness, "run", os.path.join(ROOT, "cases", "pointmass-damping.yaml"), "--method", method,
                   "--out", os.path.join(cls.runs, rid), "--duration", "1", "--quiet"]
            r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
            if not os.path.isfile(os.path.join(cls.runs, rid, "summary.json")):
                raise RuntimeError(f"{' '.join(cmd)}: no summary (exit code {r.returncode}): {r.stderr[-2000:]}")

    @classmethod
    def tearDownClass(cls):
        cls.unmount_all()

    @classmethod
    def unmount_all(cls):
        """Unmounts the tmpfs file systems a test (or an earlier, killed run) mounted under WORK."""
        work = os.path.abspath(ARGS.work)
        with open("/proc/self/mounts") as f:
            points = [l.split()[1] for l in f]
        for p in sorted(points, reverse=True):
            if p == work or p.startswith(work + "/"):
                subprocess.run(["umount", p], capture_output=True)

    def setUp(self):
        self.dir = os.path.join(self.work, self._testMethodName)
        os.makedirs(self.dir)

    def night(self, name, date, runs=None):
        """A night's runs folder: copies of the fixture runs (RUNS ids, or RUNS), with the
        nightly.json nightly.sh writes."""
        d = os.path.join(self.dir, name)
        for rid in runs or [r for r, _ in RUNS]:
            shutil.copytree(os.path.join(self.runs, rid), os.path.join(d, rid))
        info = lexdyn.history.night_info("fixture", jobs=1, duration_s=1.0, now=datetime.datetime.fromisoformat(date.replace("Z", "+00:00")))
        info.update(night=name, machine={"host": "test"})
        lexdyn.history.write_night(os.path.join(d, "nightly.json"), info)
        return d

    def mount_tmpfs(self, path, size_kb, readonly=False):
        """A tmpfs of SIZE_KB at PATH; False when the machine does not permit mounting."""
        os.makedirs(path, exist_ok=True)
        opts = f"size={size_kb}k" + (",ro" if readonly else "")
        r = subprocess.run(["mount", "-t", "tmpfs", "-o", opts, "tmpfs", path], capture_output=True, text=True)
        if r.returncode != 0:
            print(f"mount -t tmpfs refused ({r.stderr.strip()}): a file-size limit instead", file=sys.stderr)
            return False
        self.addCleanup(subprocess.run, ["umount", path], capture_output=True)
        return True

    # ------------------------------------------------------------------ a full disk
    def test_full_disk_keeps_the_previous_report(self):
        runs = self.night("n1", "2026-11-01T02:30:00Z")
        # The size of one report: the disk holds one and not a second beside it.
        probe = os.path.join(self.dir, "probe")
        r = report("--runs", runs, "--out", probe)
        self.assertEqual(r.returncode, 0, r.stderr)
        size_kb = sum(os.path.getsize(os.path.join(d, n)) for d, _, ns in os.walk(probe) for n in ns) // 1024
        disk = os.path.join(self.dir, "disk")
        on_tmpfs = self.mount_tmpfs(disk, size_kb + 320)
        out = os.path.join(disk, "report")
        history = os.path.join(disk, "history.jsonl")
        r = report("--runs", runs, "--out", out, "--history", history, "--append-history")
        self.assertEqual(r.returncode, 0, r.stderr)
        before, history_before = tree(out), read(history)
        self.assertIn("index.html", before)
        self.assertTrue(any(p.startswith("figures/") for p in before) and any(p.startswith("replay/") for p in before))
        df = os.statvfs(disk)
        free_kb = df.f_bavail * df.f_frsize // 1024
        t0 = time.time()
        if on_tmpfs:
            r = report("--runs", runs, "--out", out, "--history", history, "--append-history", "--title", "rebuilt")
            reason = "No space left on device"
        else:
            r = report("--runs", runs, "--out", out, "--history", history, "--append-history", "--title", "rebuilt",
                       limit_bytes=256 * 1024)
            reason = "File too large"
        took = time.time() - t0
        print(f"full disk ({'tmpfs' if on_tmpfs else 'file-size limit'} of {size_kb + 320} KB, report {size_kb} KB, "
              f"{free_kb} KB free): exit code {r.returncode} after {took:.1f} s: {r.stderr.strip()}", file=sys.stderr)
        self.assertEqual(r.returncode, 3, r.stderr)
        lines = error_lines(r.stderr)
        self.assertEqual(len(lines), 1, r.stderr)
        self.assertTrue(lines[0].startswith(f"report: error: {out}/"), lines[0])
        self.assertTrue(lines[0].endswith(f": {reason}"), lines[0])
        self.assertNotIn("Traceback", r.stderr)
        self.assertEqual(tree(out), before)            # the previous report, every byte
        self.assertEqual(read(history), history_before)
        self.assertEqual(leftovers(disk), [])
        # With room again the same command rebuilds the report.
        if on_tmpfs:
            subprocess.run(["mount", "-o", f"remount,size={3 * size_kb}k", disk], check=True)
            r = report("--runs", runs, "--out", out, "--history", history, "--append-history", "--title", "rebuilt")
        else:
            r = report("--runs", runs, "--out", out, "--history", history, "--append-history", "--title", "rebuilt")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("<h1>rebuilt</h1>", read(os.path.join(out, "index.html")))
        self.assertEqual(leftovers(disk), [])
        self.assertEqual(len(read(history).splitlines()), 1)

    def test_read_only_file_system(self):
        runs = self.night("n1", "2026-11-01T02:30:00Z")
        ro = os.path.join(self.dir, "ro")
        if not self.mount_tmpfs(ro, 64, readonly=True):
            # No mount: as root, permissions do not refuse a write; what remains is the message
            # of a folder that cannot be created, through a file-size limit of 0 bytes.
            r = report("--runs", runs, "--out", os.path.join(self.dir, "out"), limit_bytes=1)
            self.assertEqual(r.returncode, 3, r.stderr)
            self.assertIn("File too large", r.stderr)
            return
        r = report("--runs", runs, "--out", os.path.join(ro, "report"))
        self.assertEqual(r.returncode, 3, r.stderr)
        self.assertEqual(error_lines(r.stderr), [f"report: error: {os.path.join(ro, 'report')}: Read-only file system"])

    # ------------------------------------------------------------------ locks
    def test_two_reports_on_one_out(self):
        runs = self.night("n1", "2026-11-01T02:30:00Z")
        out = os.path.join(self.dir, "report")
        first = subprocess.Popen([PY, REPORT, "--runs", runs, "--out", out], stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True)
        lock = os.path.join(out, ".lexdyn.lock")
        deadline = time.time() + 120
        while not (os.path.isfile(lock) and read(lock).startswith(f"pid={first.pid} ")):
            self.assertIsNone(first.poll(), "the first report ended before it was seen holding its lock")
            self.assertLess(time.time(), deadline)
            time.sleep(0.01)
        # Held still while the second one tries.
        first.send_signal(signal.SIGSTOP)
        try:
            t0 = time.time()
            r = report("--runs", runs, "--out", out)
            took = time.time() - t0
        finally:
            first.send_signal(signal.SIGCONT)
        self.assertEqual(r.returncode, 2, r.stderr)
        lines = error_lines(r.stderr)
        self.assertEqual(len(lines), 1, r.stderr)
        self.assertRegex(lines[0], rf"^report: error: {re.escape(out)}: in use by another lexdyn job \(pid {first.pid}, report\.py, "
                                   r"started \d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ on \S+\); wait for it to end or give another --out$")
        print(f"second report on a locked folder: exit code 2 after {took:.2f} s", file=sys.stderr)
        self.assertTrue(read(lock).startswith(f"pid={first.pid} "))   # the holder's line untouched
        _, err = first.communicate(timeout=300)
        self.assertEqual(first.returncode, 0, err)
        self.assertTrue(os.path.isfile(os.path.join(out, "index.html")))
        # Free again once the first has ended.
        r = report("--runs", runs, "--out", out)
        self.assertEqual(r.returncode, 0, r.stderr)

    def test_nightly_on_a_locked_folder(self):
        out = os.path.join(self.dir, "night")
        os.makedirs(out)
        config = os.path.join(self.dir, "bad.yaml")
        with open(config, "w") as f:
            f.write("format: lexdyn-nightly/1\nsweeps:\n  - {file: cases/sweeps/a.yaml, points: many}\n")
        holder = subprocess.Popen(["bash", "-c", 'exec 9<>"$1/.lexdyn.lock"; flock -x 9; '
                                   'echo "pid=$$ started=2026-11-28T07:01:02Z host=elsewhere command=nightly.sh" > "$1/.lexdyn.lock"; '
                                   'echo locked; read -r _', "_", out],
                                  stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        self.assertEqual(holder.stdout.readline().strip(), "locked")
        cmd = ["bash", NIGHTLY, "--out", out, "--config", config, "--no-build", "--no-ctest",
               "--history", os.path.join(self.dir, "history.jsonl")]
        try:
            r = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
        finally:
            holder.stdin.close()
            holder.wait(timeout=30)
            holder.stdout.close()
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertEqual(error_lines(r.stderr), [f"nightly: error: {out}: in use by another lexdyn job (pid {holder.pid}, nightly.sh, "
                                                 "started 2026-11-28T07:01:02Z on elsewhere); wait for it to end or give another --out"])
        # The holder has ended: its lock is taken over (the job then stops at the bad configuration).
        ino = os.stat(os.path.join(out, ".lexdyn.lock")).st_ino
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("sweeps[0].points: expected a positive integer", r.stderr)
        self.assertRegex(read(os.path.join(out, ".lexdyn.lock")), r"^pid=\d+ started=\S+Z host=\S+ command=nightly\.sh\n$")
        self.assertEqual(os.stat(os.path.join(out, ".lexdyn.lock")).st_ino, ino)

    def test_stale_lock_is_taken_over(self):
        runs = self.night("n1", "2026-11-01T02:30:00Z")
        out = os.path.join(self.dir, "report")
        os.makedirs(out)
        pid = dead_pid()
        lock = os.path.join(out, ".lexdyn.lock")
        with open(lock, "w") as f:
            f.write(f"pid={pid} started=2026-11-27T07:01:02Z host=gone command=report.py\n")
        ino = os.stat(lock).st_ino
        # What a report killed while building leaves: its staging folder.
        os.makedirs(os.path.join(out, f".staging-{pid}", "figures"))
        with open(os.path.join(out, f".staging-{pid}", "figures", "leftover"), "w") as f:
            f.write("x")
        p = subprocess.Popen([PY, REPORT, "--runs", runs, "--out", out], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        printed, err = p.communicate(timeout=300)
        self.assertEqual(p.returncode, 0, err)
        self.assertRegex(read(lock), rf"^pid={p.pid} started=\d{{4}}-\d\d-\d\dT\d\d:\d\d:\d\dZ host=\S+ command=report\.py\n$")
        self.assertEqual(os.stat(lock).st_ino, ino)     # the same file, never removed
        self.assertEqual(leftovers(out), [])
        # The lock file is not counted as a file of the report.
        m = re.search(r"\((\d+) files,", printed)
        self.assertIsNotNone(m, printed + err)
        self.assertEqual(int(m.group(1)), len(tree(out)))

    def test_bad_out(self):
        runs = self.night("n1", "2026-11-01T02:30:00Z")
        a_file = os.path.join(self.dir, "a_file")
        with open(a_file, "w") as f:
            f.write("not a folder\n")
        for out in (a_file, os.path.join(a_file, "report")):
            r = report("--runs", runs, "--out", out)
            self.assertEqual(r.returncode, 2, r.stderr)
            self.assertEqual(error_lines(r.stderr), [f"report: error: {out}: cannot create the output folder: {a_file} exists and is not a folder"])
        self.assertEqual(read(a_file), "not a folder\n")

    # ------------------------------------------------------------------ the history
    def test_damaged_history_lines_are_skipped(self):
        n1 = self.night("n1", "2026-11-01T02:30:00Z")
        n2 = self.night("n2", "2026-11-02T02:30:00Z")
        history = os.path.join(self.dir, "history.jsonl")
        r = report("--runs", n1, "--out", os.path.join(self.dir, "report1"), "--history", history, "--append-history")
        self.assertEqual(r.returncode, 0, r.stderr)
        good = read(history)
        rec = json.loads(good)
        damages = {  # kind: (the damaged history's text, its damaged line, the warning's field and text)
            "cut last line": (good + good[:57], 2, "expected one JSON record per line, found a syntax error"),
            "garbage line": (good + "\x00\x01 garbage }{\n", 2, "expected one JSON record per line, found a syntax error"),
            "other format": (json.dumps(dict(rec, format="lexdyn-nightly-history/2", night="nx")) + "\n" + good, 1,
                             "format: expected 'lexdyn-nightly-history/1', found 'lexdyn-nightly-history/2'"),
            "runs as a list": (good + json.dumps(dict(rec, night="ny", runs=list(rec["runs"]))) + "\n", 2,
                               "runs: expected an object of runs by id, found a list"),
        }
        for kind, (text, line, what) in damages.items():
            with self.subTest(kind):
                with open(history, "w") as f:
                    f.write(text)
                damaged_line = text.split("\n")[line - 1]
                out = os.path.join(self.dir, "report-" + kind.replace(" ", "-"))
                # --strict-history refuses, naming the file, the line and the field; nothing changes.
                r = report("--runs", n2, "--out", out, "--history", history, "--append-history", "--strict-history")
                self.assertEqual(r.returncode, 2, r.stderr)
                lines = error_lines(r.stderr)
                self.assertEqual(len(lines), 1, r.stderr)
                self.assertTrue(lines[0].startswith(f"report: error: {history}:{line}: "), lines[0])
                self.assertIn(what, lines[0])
                self.assertEqual(read(history), text)
                self.assertFalse(os.path.exists(os.path.join(out, "index.html")))
                # Without it: the report, the warning on the page and printed, the night appended.
                r = report("--runs", n2, "--out", out, "--history", history, "--append-history")
                self.assertEqual(r.returncode, 0, r.stderr)
                self.assertIn(f"report: warning: {history}:{line}: ", r.stderr)
                self.assertIn(what, r.stderr)
                page = read(os.path.join(out, "index.html"))
                section = page[page.index("<section id='changes'>"):page.index("<section id='verdicts'>")]
                self.assertIn("id='history-warnings'", section)
                self.assertIn(f"{history}:{line}: ", section)
                self.assertIn("Compared with night <b>n1</b>", section)
                self.assertIn("id='trend-history-note'", page)
                after = read(history).split("\n")
                self.assertEqual([json.loads(l)["night"] for l in after[:2]], ["n1", "n2"])
                self.assertEqual(after[2:], [damaged_line, ""])    # kept as it was, after the records
                # The next night reads the history the same way.
                r = report("--runs", n2, "--out", out, "--history", history)
                self.assertEqual(r.returncode, 0, r.stderr)

    def test_date_order_rebuilt_night_and_since_last_night(self):
        nights = {name: self.night(name, f"2026-11-0{i}T02:30:00Z") for i, name in ((1, "n1"), (2, "n2"), (3, "n3"))}
        history = os.path.join(self.dir, "history.jsonl")

        def build(name, runs=None):
            r = report("--runs", runs or nights[name], "--out", os.path.join(self.dir, "report-" + name),
                       "--history", history, "--append-history")
            self.assertEqual(r.returncode, 0, r.stderr)
            page = read(os.path.join(self.dir, "report-" + name, "index.html"))
            m = re.search(r"Compared with night <b>([^<]*)</b>", page)
            return m.group(1) if m else None

        def file_nights():
            with open(history) as f:
                return [json.loads(l)["night"] for l in f]

        self.assertIsNone(build("n1"))
        self.assertEqual(build("n3"), "n1")
        self.assertEqual(build("n2"), "n1")          # not n3: the latest night dated before n2
        self.assertEqual(file_nights(), ["n1", "n2", "n3"])
        # n2 rebuilt with the GN run only: its record replaced in place, nothing added.
        shutil.rmtree(os.path.join(nights["n2"], "pointmass-damping.wls"))
        self.assertEqual(build("n2"), "n1")
        self.assertEqual(file_nights(), ["n1", "n2", "n3"])
        with open(history) as f:
            recs = [json.loads(l) for l in f]
        self.assertEqual(sorted(recs[1]["runs"]), ["pointmass-damping.gn"])
        self.assertEqual(sorted(recs[2]["runs"]), ["pointmass-damping.gn", "pointmass-damping.wls"])
        # n3 compares with n2 (now missing the WLS run there, so it is "added").
        self.assertEqual(build("n3"), "n2")
        page = read(os.path.join(self.dir, "report-n3", "index.html"))
        self.assertIn("<td>run added</td><td>pointmass-damping.wls</td>", page)
        self.assertIn("2 earlier night(s)", page)

    def test_nan_is_marked_never_shown(self):
        n1 = self.night("n1", "2026-11-01T02:30:00Z")
        history = os.path.join(self.dir, "history.jsonl")
        r = report("--runs", n1, "--out", os.path.join(self.dir, "report1"), "--history", history, "--append-history")
        self.assertEqual(r.returncode, 0, r.stderr)
        # The history's figures of n1 damaged: NaN and Infinity where the report wrote numbers.
        text = read(history)
        text = re.sub(r'("final_error": )[-0-9.e]+', r"\1NaN", text, count=1)
        text = re.sub(r'("tick_p50_us": )[-0-9.e]+', r"\1Infinity", text, count=1)
        self.assertEqual(text.count("NaN") + text.count("Infinity"), 2)
        with open(history, "w") as f:
            f.write(text)
        # n2's GN summary damaged: NaN and Infinity where the harness wrote numbers.
        n2 = self.night("n2", "2026-11-02T02:30:00Z")
        path = os.path.join(n2, "pointmass-damping.gn", "summary.json")
        with open(path) as f:
            summary = json.load(f)
        summary["realtime_factor"] = float("nan")
        summary["timing_us"]["tick"]["median"] = float("inf")
        summary["checks"][0]["value"] = float("nan")
        with open(path, "w") as f:
            json.dump(summary, f, indent=1)        # Python writes them as NaN and Infinity
        self.assertEqual(read(path).count("NaN") + read(path).count("Infinity"), 3)
        out = os.path.join(self.dir, "report2")
        r = report("--runs", n2, "--out", out, "--history", history, "--append-history")
        self.assertEqual(r.returncode, 0, r.stderr)
        page = read(os.path.join(out, "index.html"))
        self.assertIn(DAMAGED, page)
        shown = cells(page)
        for c in shown:
            self.assertNotRegex(c, r"(?i)(^|[\s/(])(-?nan|-?inf(inity)?)($|[\s/)])", c)
            self.assertNotRegex(c, r"(^|\s)- %", c)
        # The damaged real-time factor of GN in its method table and in the trend table.
        self.assertIn(DAMAGED, page[page.index("id='methods-pointmass-damping'"):page.index("</table>", page.index("id='methods-pointmass-damping'"))])
        trend = page[page.index("id='trend-table'"):]
        trend = trend[:trend.index("</table>")]
        self.assertIn(DAMAGED, trend)
        # n1's NaN final error is no point of a band: GN's final error has no earlier value.
        gn_row = re.search(r"<tr><td>pointmass-damping\.gn</td>(.*?)</tr>", trend).group(1)
        final_cell = re.findall(r"<td[^>]*>(.*?)</td>", gn_row)[0]
        self.assertNotIn("band", final_cell)
        self.assertIn("runs.pointmass-damping.gn.final_error: expected a finite number, found NaN", r.stderr)
        self.assertIn(f"{path}: realtime_factor: expected a finite number, found NaN", r.stderr)
        # n2's record is JSON: the damaged figures are null; n1's line is kept as it was.
        lines = read(history).splitlines()
        self.assertEqual(lines[0], text.splitlines()[0])
        self.assertNotIn("NaN", lines[1])
        self.assertNotIn("Infinity", lines[1])
        rec = json.loads(lines[1])
        self.assertIsNone(rec["runs"]["pointmass-damping.gn"]["realtime_factor"])
        # --strict-history refuses the damaged figure of n1.
        r = report("--runs", n2, "--out", out, "--history", history, "--strict-history")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn(f"{history}:1: runs.pointmass-damping.gn.final_error: expected a finite number, found NaN", r.stderr)


if __name__ == "__main__":
    suite_options.main(sys.modules[__name__], "--harness", "--work")
