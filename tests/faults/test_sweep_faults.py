#!/usr/bin/python3
"""Faults in sweeps and runs (docs/architecture.md, "Faults"): every fault below must end in
the result of an uninterrupted sweep after at most one resume, or in a clear refusal; never in a
wrong record, failure, failure-database entry or exit code, never in an abort.

Usage: test_sweep_faults.py --harness PATH --source DIR --work DIR [--seed N] [--only NAME,...]

Faults: SIGKILL and SIGTERM to workers and to the driver at seeded random moments (running
points and shrinking), two jobs on one folder (runs and sweeps), damaged state files (a cut
result.json of a pending run, a cut points/I.json, a garbage shrink cache, a damaged
sweep.txt), a full disk (a small tmpfs; where mounting is not permitted, a file-size limit),
runs whose disk fills.
"""
import argparse
import json
import os
import random
import resource
import shutil
import signal
import subprocess
import sys
import time

SWEEP = "cases/sweeps/pointmass-damping.yaml"
POINTS = "8"
FAILED = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        FAILED.append(what)


def strip_wall(x):
    """A record without its wall-clock figures (never deterministic)."""
    if isinstance(x, dict):
        return {k: strip_wall(v) for k, v in x.items() if k != "wall_s"}
    if isinstance(x, list):
        return [strip_wall(v) for v in x]
    return x


def outcome(out):
    """What a finished sweep says: its records, its summary's verdicts and failures."""
    recs = [strip_wall(json.loads(line)) for line in open(os.path.join(out, "results.jsonl"))]
    summ = json.load(open(os.path.join(out, "summary.json")))
    keep = {k: summ[k] for k in ("failed_points", "completed", "failures", "checks")}
    db = os.path.join(out, "..", os.path.basename(out) + ".db")
    return {"records": recs, "summary": strip_wall(keep), "db": open(db).read() if os.path.exists(db) else ""}


class Env:
    def __init__(self, a):
        self.h, self.src, self.work = os.path.abspath(a.harness), os.path.abspath(a.source), a.work

    def sweep_cmd(self, out, *extra):
        return [self.h, "sweep", "run", os.path.join(self.src, SWEEP), "--out", out, "-j", "2", "--points", POINTS,
                "--db", out + ".db", "--quiet", *extra]

    def sweep(self, out, *extra, **kw):
        return subprocess.run(self.sweep_cmd(out, *extra), capture_output=True, text=True, cwd=self.src, **kw)

    def start(self, out, *extra):
        return subprocess.Popen(self.sweep_cmd(out, *extra), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=self.src)

    def fresh(self, name):
        d = os.path.join(self.work, name)
        shutil.rmtree(d, ignore_errors=True)
        for f in (d + ".db", d + ".db.lock"):
            if os.path.exists(f):
                os.remove(f)
        return d


def wait_for_lock(out, pid, limit_s=60):
    """Waits until the job PID holds OUT's lock (a loaded machine may take seconds to start it)."""
    t0 = time.time()
    while time.time() - t0 < limit_s:
        try:
            if open(os.path.join(out, ".lexdyn.lock")).read().startswith(f"pid={pid} "):
                return True
        except OSError:
            pass
        time.sleep(0.01)
    return False


def workers_of(out):
    """The pids of the `sweep point` processes writing into OUT."""
    pids = []
    for p in os.listdir("/proc"):
        if not p.isdigit():
            continue
        try:
            argv = open(f"/proc/{p}/cmdline", "rb").read().split(b"\0")
        except OSError:
            continue
        if b"point" in argv and any(a.startswith(out.encode()) for a in argv):
            pids.append(int(p))
    return pids


def resume_until_done(env, out, tries=3):
    """Resumes a sweep until it has a summary (a run lost twice makes a sweep exit 3)."""
    r = None
    for _ in range(tries):
        r = env.sweep(out)
        if r.returncode in (0, 1) and os.path.exists(os.path.join(out, "summary.json")):
            return r
    return r


def test_worker_kills(env, base, rng):
    shrink_kills = [0]
    for k in range(6):
        sig = signal.SIGKILL if k % 2 == 0 else signal.SIGTERM
        out = env.fresh(f"worker-kill-{k}")
        p = env.start(out)
        kills = 0
        t0 = time.time()
        # Three moments over the sweep's length: running points, shrinking, replaying.
        for when in sorted(rng.uniform(0.2, base["wall"] * 1.1) for _ in range(3)):
            while p.poll() is None and time.time() - t0 < when:
                time.sleep(0.02)
            if p.poll() is not None:
                break
            pids = workers_of(out)
            if pids:
                pid = rng.choice(pids)
                try:
                    during_shrink = b"/shrink/" in open(f"/proc/{pid}/cmdline", "rb").read()
                    os.kill(pid, sig)
                    kills += 1
                    shrink_kills[0] += 1 if during_shrink else 0
                except (ProcessLookupError, FileNotFoundError):
                    pass
        _, err = p.communicate(timeout=300)
        check(p.returncode in (0, 1, 3), f"{sig.name} to {kills} worker(s) #{k}: exit {p.returncode} (no abort)")
        check("lost" not in err or p.returncode == 3, f"{sig.name} #{k}: a lost run makes the sweep exit 3")
        r = resume_until_done(env, out) if p.returncode == 3 else p
        check(outcome(out) == base["outcome"], f"{sig.name} to {kills} worker(s) #{k}: records, failures and database as uninterrupted")
        check(r.returncode == base["code"], f"{sig.name} #{k}: exit code {r.returncode} as uninterrupted ({base['code']})")
    check(shrink_kills[0] > 0, f"{shrink_kills[0]} of the kills hit a shrinking trial")


def test_driver_kills(env, base, rng):
    for k in range(6):
        sig = signal.SIGKILL if k % 2 == 0 else signal.SIGTERM
        out = env.fresh(f"driver-kill-{k}")
        p = env.start(out)
        time.sleep(rng.uniform(0.3, base["wall"] * 0.95))
        p.send_signal(sig)
        p.communicate(timeout=300)
        # 1: the sweep was done before the signal came.
        want = (-9, 1) if sig == signal.SIGKILL else (143, 1)
        check(p.returncode in want, f"{sig.name} to the driver #{k}: exit {p.returncode}")
        r = env.sweep(out)
        check(outcome(out) == base["outcome"], f"{sig.name} to the driver #{k}, resumed: as uninterrupted")
        check(r.returncode == base["code"], f"{sig.name} to the driver #{k}: resumed exit code {r.returncode}")


def test_two_sweeps(env, base):
    out = env.fresh("two-sweeps")
    p = env.start(out)
    check(wait_for_lock(out, p.pid), "the first sweep holds the folder's lock")
    r = env.sweep(out)
    check(r.returncode == 2 and f"pid {p.pid}" in r.stderr and "in use by another lexdyn job" in r.stderr,
          f"a second sweep on one folder exits 2 naming the first ({r.returncode}: {r.stderr.strip()[:200]})")
    p.communicate(timeout=300)
    check(outcome(out) == base["outcome"] and p.returncode == base["code"], "the first sweep's result is the uninterrupted one")


def test_two_runs(env):
    out = env.fresh("two-runs")
    case = os.path.join(env.src, "cases/exp1.yaml")
    p = subprocess.Popen([env.h, "run", case, "--out", out, "--duration", "20", "--quiet"], stderr=subprocess.PIPE, text=True)
    check(wait_for_lock(out, p.pid), "the first run holds the folder's lock")
    r = subprocess.run([env.h, "run", os.path.join(env.src, "cases/stand.yaml"), "--out", out, "--quiet"], capture_output=True, text=True)
    p.communicate(timeout=300)
    check(r.returncode == 2 and f"pid {p.pid}" in r.stderr, f"a second run on one folder exits 2 naming the first: {r.stderr.strip()[:200]}")
    s = json.load(open(os.path.join(out, "summary.json")))
    trace = open(os.path.join(out, "trace.csv")).read()
    check(p.returncode == 0 and s["case"].startswith("exp1") and "# end: completed" in trace and "stand" not in open(os.path.join(out, "case.yaml")).read().split("\n")[0],
          "the first run's trace, summary and case are its own")
    # A stale lock file (its process ended) is taken over.
    open(os.path.join(out, ".lexdyn.lock"), "w").write("pid=999999 started=2020-01-01T00:00:00Z host=x command=lexdyn-harness run old\n")
    r = subprocess.run([env.h, "run", os.path.join(env.src, "cases/stand.yaml"), "--out", out, "--quiet", "--duration", "0.5"], capture_output=True, text=True)
    check(r.returncode == 0, f"a stale lock is taken over (exit {r.returncode})")


def test_damaged_state(env, base):
    src = os.path.join(env.work, "base")
    # A pending run's result.json cut (its point not recorded yet), and a cut point record.
    out = env.fresh("damaged-result")
    shutil.copytree(src, out)
    shutil.copy(src + ".db", out + ".db")
    os.remove(os.path.join(out, "points", "000003.json"))
    os.remove(os.path.join(out, "summary.json"))
    res = os.path.join(out, "runs", "000003", "wls", "result.json")
    text = open(res).read()
    open(res, "w").write(text[: len(text) // 2])
    pt = os.path.join(out, "points", "000005.json")
    text = open(pt).read()
    open(pt, "w").write(text[: len(text) // 3])
    r = env.sweep(out)
    check(r.returncode == base["code"] and outcome(out) == base["outcome"], f"a cut result.json and a cut points/I.json are made again (exit {r.returncode})")
    # Garbage in the shrink cache: those trials are run again.
    out = env.fresh("damaged-cache")
    shutil.copytree(src, out)
    shutil.copy(src + ".db", out + ".db")
    with open(os.path.join(out, "shrink", "cache.jsonl"), "a") as f:
        f.write('{"key": "x", "result": {"status": "crashed"}}\ngarbage\n{"key":')
    lines = open(os.path.join(out, "shrink", "cache.jsonl")).read().split("\n")
    open(os.path.join(out, "shrink", "cache.jsonl"), "w").write("\n".join(lines[:3] + ['{"key": "cut'] + lines[5:]))
    r = env.sweep(out)
    check(r.returncode == base["code"] and outcome(out) == base["outcome"], f"a damaged shrink cache: as uninterrupted (exit {r.returncode})")
    # Lines of the failure database that are not failures are named (file and line) and skipped.
    out = env.fresh("damaged-db")
    with open(out + ".db", "w") as f:
        f.write(open(src + ".db").read() + '7\n{"sweep": "pointmass-damping", "method": "wls", "check": "no_overshoot", "values": {"controller.params.damping": 0.5}}\n{"sweep"')
    r = env.sweep(out)
    got = outcome(out)
    check(r.returncode == base["code"] and got["records"] == base["outcome"]["records"] and got["summary"] == base["outcome"]["summary"]
          and f"{out}.db:2:" in r.stderr and f"{out}.db:3:" in r.stderr and f"{out}.db:4:" in r.stderr,
          f"a damaged failure database: its bad lines named and skipped (exit {r.returncode})")
    # A damaged sweep.txt is named as damaged, not as another sweep.
    out = env.fresh("damaged-sweeptxt")
    shutil.copytree(src, out)
    st = os.path.join(out, "sweep.txt")
    text = open(st).read()
    open(st, "w").write(text[: len(text) - 40])
    r = env.sweep(out)
    check(r.returncode == 2 and "damaged" in r.stderr and "sweep.txt" in r.stderr, f"a cut sweep.txt is refused as damaged: {r.stderr.strip()[:200]}")


def test_database_lock_wait(env, base):
    """A sweep waiting for the failure database's lock (another job writes it) ends on SIGTERM
    at once (exit 143, the database untouched); once the lock is free it finishes as usual."""
    import fcntl
    src = os.path.join(env.work, "base")
    out = env.fresh("db-lock")
    shutil.copytree(src, out)
    os.remove(os.path.join(out, "summary.json"))  # the merge (shrink from the cache, database) is left
    shutil.copy(src + ".db", out + ".db")
    before = open(out + ".db").read()
    holder = open(out + ".db.lock", "a+")
    fcntl.flock(holder, fcntl.LOCK_EX)
    p = env.start(out)
    time.sleep(3.0)  # the points and the shrinks come from what is stored: the driver now waits for the lock
    waiting = p.poll() is None
    t0 = time.time()
    p.send_signal(signal.SIGTERM)
    try:
        p.wait(timeout=10)
    except subprocess.TimeoutExpired:
        p.kill()
        p.wait()
    took = time.time() - t0
    check(waiting and p.returncode == 143 and took < 2.0 and open(out + ".db").read() == before,
          f"a sweep waiting for the database's lock ends on SIGTERM (exit {p.returncode} after {took:.2f} s), the database untouched")
    fcntl.flock(holder, fcntl.LOCK_UN)
    holder.close()
    r = env.sweep(out)
    check(r.returncode == base["code"] and outcome(out) == base["outcome"], f"then, with the lock free, as uninterrupted (exit {r.returncode})")


def test_concurrent_shrinks(env):
    """Two failures of one method shrink at once and may ask for the same trial: it runs once."""
    text = open(os.path.join(env.src, SWEEP)).read()
    text = text.replace("base: ../pointmass-damping.yaml", "base: " + os.path.join(env.src, "cases/pointmass-damping.yaml"))
    text = text.replace("checks: [no_overshoot, controller_ok]", "checks: [no_overshoot, closed_form_eq49, controller_ok]")
    sweep = os.path.join(env.work, "two-failures.yaml")
    open(sweep, "w").write(text)
    outs = []
    for k in range(2):
        out = env.fresh(f"two-failures-{k}")
        r = subprocess.run([env.h, "sweep", "run", sweep, "--out", out, "-j", "2", "--points", POINTS, "--no-db", "--quiet"],
                           capture_output=True, text=True, cwd=env.work)
        cache = open(os.path.join(out, "shrink", "cache.jsonl")).read()
        check(r.returncode == 1 and "bad_input" not in cache and "in use" not in cache, f"two shrinks of one method #{k}: no trial refused (exit {r.returncode})")
        outs.append(outcome(out))
    check(outs[0] == outs[1], "two shrinks of one method: the same shrunk failures every time")


def test_stopped_worker(env, base):
    """A worker stopped (SIGSTOP) for longer than the timeout, then continued: not a timeout."""
    out = env.fresh("stopped-worker")
    p = env.start(out, "--timeout", "3")
    pids = []
    while p.poll() is None and not pids:
        time.sleep(0.05)
        pids = workers_of(out)
    if pids:
        os.kill(pids[0], signal.SIGSTOP)
        time.sleep(4.5)
        os.kill(pids[0], signal.SIGCONT)
    p.communicate(timeout=300)
    check(bool(pids) and p.returncode == base["code"] and outcome(out) == base["outcome"], f"a worker stopped for 4.5 s of a 3 s timeout: as uninterrupted (exit {p.returncode})")


def small_fs(path, size):
    """Mounts a tmpfs of SIZE at PATH; False where the machine does not allow it."""
    os.makedirs(path, exist_ok=True)
    subprocess.run(["umount", path], capture_output=True)
    return subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", path], capture_output=True).returncode == 0


def limit_file_size(nbytes):
    def f():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (nbytes, nbytes))
    return f


def test_full_disk(env, base):
    mnt = os.path.join(env.work, "small-fs")
    mounted = small_fs(mnt, "400k")
    print(f"note: full disk through {'a 400 kB tmpfs' if mounted else 'a file-size limit (mount not permitted)'}", flush=True)
    try:
        # A run: exit 3 with the system's reason, found at the first failed write.
        out = os.path.join(mnt if mounted else env.work, "run-full")
        shutil.rmtree(out, ignore_errors=True)
        cmd = [env.h, "run", os.path.join(env.src, "cases/exp1.yaml"), "--out", out, "--duration", "20", "--quiet"]
        r = subprocess.run(cmd, capture_output=True, text=True, preexec_fn=None if mounted else limit_file_size(150_000))
        reason = "No space left on device" if mounted else "File too large"
        check(r.returncode == 3 and reason in r.stderr, f"a run whose disk fills exits 3 with the reason: {r.stderr.strip()[-200:]}")
        check("the run stopped at t = " in r.stderr and "t = 20" not in r.stderr, "the failed write stops the run at once")
        if not mounted:
            return
        shutil.rmtree(out, ignore_errors=True)
        # A sweep: exit 3 with the reason, no abort, at every size tried (the disk fills while
        # the sweep folder is made, while points run, while the summary is written); after room
        # is made, a resume gives the uninterrupted result.
        out = os.path.join(mnt, "sweep-full")
        for size in ("8k", "48k", "160k", "400k", "900k"):
            subprocess.run(["umount", mnt], capture_output=True)
            small_fs(mnt, size)
            r = subprocess.run(env.sweep_cmd(out), capture_output=True, text=True, cwd=env.src)
            check(r.returncode == 3 and "No space left on device" in r.stderr and "terminate" not in r.stderr and "internal error" not in r.stderr,
                  f"a sweep whose {size} disk fills exits 3 with the reason: {r.stderr.strip()[-300:]}")
            subprocess.run(["mount", "-o", "remount,size=64m", mnt], check=True)
            r = env.sweep(out)
            check(r.returncode == base["code"] and outcome(out) == base["outcome"], f"{size}: resumed with room: as uninterrupted (exit {r.returncode})")
        # The disk fills while the failures are shrunk: the trials that cannot write are lost,
        # nothing is cached for them, no summary and no database entry are written.
        for d in ("shrink", "failures"):
            shutil.rmtree(os.path.join(out, d))
        os.remove(os.path.join(out, "summary.json"))
        os.remove(out + ".db")
        st = os.statvfs(mnt)
        filler = os.path.join(mnt, "filler")
        with open(filler, "wb") as f:
            f.write(b"\0" * (st.f_bavail * st.f_frsize - 64 * 1024))
        r = subprocess.run([env.h, "sweep", "merge", os.path.join(env.src, SWEEP), "--out", out, "-j", "2", "--points", POINTS, "--db", out + ".db"],
                           capture_output=True, text=True, cwd=env.src)
        check(r.returncode == 3 and "No space left on device" in r.stderr and "terminate" not in r.stderr,
              f"a disk that fills while shrinking: exit 3 with the reason: {r.stderr.strip()[-300:]}")
        check(not os.path.exists(os.path.join(out, "summary.json")) and not os.path.exists(out + ".db"), "no summary and no database entry")
        os.remove(filler)
        r = env.sweep(out)
        check(r.returncode == base["code"] and outcome(out) == base["outcome"], f"resumed with room: as uninterrupted (exit {r.returncode})")
    finally:
        if mounted:
            subprocess.run(["umount", mnt], capture_output=True)


def test_output_errors(env):
    r = subprocess.run([env.h, "run", os.path.join(env.src, "cases/stand.yaml"), "--out", "/proc/version/x", "--quiet"], capture_output=True, text=True)
    check(r.returncode == 2 and "exists and is not a folder" in r.stderr, f"an --out below a file is bad input: {r.stderr.strip()}")
    ro = os.path.join(env.work, "read-only")
    os.makedirs(ro, exist_ok=True)
    if small_fs(ro, "64k"):
        subprocess.run(["mount", "-o", "remount,ro", ro], check=True)
        r = subprocess.run([env.h, "run", os.path.join(env.src, "cases/stand.yaml"), "--out", os.path.join(ro, "x"), "--quiet"], capture_output=True, text=True)
        subprocess.run(["umount", ro], capture_output=True)
        check(r.returncode == 3 and "Read-only file system" in r.stderr, f"an --out on a read-only file system exits 3 with the reason: {r.stderr.strip()}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--harness", required=True)
    ap.add_argument("--source", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--seed", type=int, default=20261128)
    ap.add_argument("--only")
    a = ap.parse_args()
    a.work = os.path.abspath(a.work)
    os.makedirs(a.work, exist_ok=True)
    env = Env(a)
    rng = random.Random(a.seed)
    out = env.fresh("base")
    t0 = time.time()
    r = env.sweep(out)
    base = {"outcome": outcome(out), "code": r.returncode, "wall": time.time() - t0}
    check(r.returncode == 1 and base["outcome"]["summary"]["failures"][0]["shrunk"], f"the uninterrupted sweep fails and shrinks (exit {r.returncode}, {base['wall']:.1f} s)")
    tests = {
        "two_runs": lambda: test_two_runs(env),
        "output_errors": lambda: test_output_errors(env),
        "two_sweeps": lambda: test_two_sweeps(env, base),
        "damaged_state": lambda: test_damaged_state(env, base),
        "database_lock_wait": lambda: test_database_lock_wait(env, base),
        "full_disk": lambda: test_full_disk(env, base),
        "concurrent_shrinks": lambda: test_concurrent_shrinks(env),
        "stopped_worker": lambda: test_stopped_worker(env, base),
        "worker_kills": lambda: test_worker_kills(env, base, rng),
        "driver_kills": lambda: test_driver_kills(env, base, rng),
    }
    only = a.only.split(",") if a.only else list(tests)
    for name in only:
        print(f"== {name}", flush=True)
        tests[name]()
    print(f"{len(FAILED)} failed", flush=True)
    return 1 if FAILED else 0


if __name__ == "__main__":
    sys.exit(main())
