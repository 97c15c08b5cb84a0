"""The compiled module lexdyn._core (python/src/core.cpp; docs/python.md, "Bindings"), imported from
the build tree (ctest python.bindings: PYTHONPATH=build/python): a solve from Python equals
lexdyn-solve's bit for bit, the robot model's M, centre of mass and Jacobians are sound, and a
case run from Python equals `lexdyn-harness run`'s. A missing module fails (never skips)."""
import glob
import json
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import lexdyn

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
HRP2 = os.path.join(ROOT, "models", "hrp2kai_like")
POINTMASS = os.path.join(ROOT, "cases", "pointmass-damping.yaml")
GN = "runs/pointmass-damping.gn"


def bits(a):
    """The bit patterns of a float64 array (so that -0.0 != 0.0 and NaN == NaN of the same bits)."""
    return np.ascontiguousarray(np.asarray(a, dtype=np.float64)).view(np.uint64)


def assert_same_bits(a, b, what=""):
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    assert a.shape == b.shape, what
    if not np.array_equal(bits(a), bits(b)):
        i = np.flatnonzero(bits(a).ravel() != bits(b).ravel())[0]
        pytest.fail(f"{what}: first difference at {np.unravel_index(i, a.shape)}: {a.ravel()[i]!r} != {b.ravel()[i]!r}")


def tool(name):
    path = os.environ.get({"lexdyn-solve": "LEXDYN_SOLVE", "lexdyn-harness": "LEXDYN_HARNESS"}[name])
    if not path or not os.access(path, os.X_OK):
        pytest.fail(f"the ctest environment names {name} (LEXDYN_SOLVE / LEXDYN_HARNESS)")
    return path


def lexdyn_solve(path, *args):
    p = subprocess.run([tool("lexdyn-solve"), *args, path], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return p.stdout.strip()


@pytest.fixture(scope="module")
def problems(outputs):
    files = sorted(glob.glob(os.path.join(outputs, "problems", "exp1.gn", "tick_*.json")))
    assert len(files) == 2, "write_outputs.sh dumps two ticks of exp1 (GN)"
    return files


@pytest.fixture(scope="module")
def hrp2():
    return lexdyn.RobotModel.load(os.path.join(HRP2, "hrp2kai_like.urdf"), os.path.join(HRP2, "hrp2kai_like.yaml"))


# ------------------------------------------------------------------ the module
def test_the_compiled_module_is_the_build_trees():
    assert lexdyn.BINDINGS, "lexdyn._core is not importable (build the target lexdyn_python_core)"
    build = os.environ.get("LEXDYN_BUILD_DIR")
    if not build:
        pytest.fail("LEXDYN_BUILD_DIR names the build directory (set by ctest)")
    here = os.path.join(os.path.realpath(build), "python", "lexdyn")
    assert os.path.dirname(os.path.realpath(lexdyn.__file__)) == here
    assert os.path.dirname(os.path.realpath(lexdyn._core.__file__)) == here
    for name in lexdyn.__all__:
        assert hasattr(lexdyn, name), name
    assert issubclass(lexdyn.InputError, ValueError)


# ------------------------------------------------------------------ solver
def test_a_dumped_problem_solves_as_lexdyn_solve_does(problems):
    for path in problems:
        problem = lexdyn.load_problem(path)
        assert problem.level_count > 5 and problem.levels[0]["kind"] == "bounds"
        # The controller's solver options, which the dump carries and lexdyn-solve runs.
        options = lexdyn.load_solver_options(path)
        assert options is not None and options.split_from_variable > 0
        result = lexdyn.solve(problem, options=options)
        assert result.status == "solved"
        # The same text as lexdyn-solve prints (shortest round-trip numbers), and the same bits.
        text = lexdyn.result_to_json(problem, result, options=options, options_from="the problem file")
        assert text == lexdyn_solve(path)
        assert lexdyn.result_to_json(problem, result, details=True, options=options,
                                     options_from="the problem file") == lexdyn_solve(path, "--details")
        # The solver's defaults (split coordinates off) reach the same optimum, by other rounding.
        default = lexdyn.solve(problem)
        assert default.status == "solved"
        assert lexdyn.result_to_json(problem, default, options=lexdyn.Options(),
                                     options_from="the solver's defaults") == lexdyn_solve(path, "--default-options")
        cli = json.loads(lexdyn_solve(path))
        assert_same_bits(result.x, cli["x"], "x")
        assert_same_bits(result.level_violation, cli["level_violation"], "level_violation")
        assert result.iterations == cli["iterations"] and result.reason == cli["reason"]
        assert len(result.violation) == problem.level_count == len(result.active)


def test_restarts_after_a_bound_change_are_counted():
    # A 7-variable problem whose search fixes a force (tests/data/solver/restart_unit_row.json):
    # the solver restarts after that bound change instead of factorising every level again, and
    # reaches the same bits of x as with the option off.
    path = os.path.join(ROOT, "tests", "data", "solver", "restart_unit_row.json")
    problem = lexdyn.load_problem(path)
    options = lexdyn.load_solver_options(path)
    options.restart_after_bound_change = True
    on = lexdyn.solve(problem, options=options)
    options.restart_after_bound_change = False
    off = lexdyn.solve(problem, options=options)
    assert on.status == off.status == "solved"
    assert on.bound_change_restarts > 0 and off.bound_change_restarts == 0
    assert on.factorizations < off.factorizations
    assert_same_bits(on.x, off.x, "x")


def test_swap_reflectors_and_a_cold_restart_after_an_unbroken_cycle():
    # Two ticks of the GN controller (tests/data/solver/warm_cycle_*.json): warm-started from the
    # first tick's answer, the second's search repeats a cycle the raised tolerances do not break
    # and starts again cold; with the generic arithmetic for the unit columns' reflectors
    # (swap_reflectors off) it takes another path. Both end at the same optimum. The cycle is in
    # the rounding of the build that dumped the ticks, which did not project the level before the
    # last there; the projected unit suffix off keeps that rounding (test_solver_paper.cpp).
    data = os.path.join(ROOT, "tests", "data", "solver")
    first = lexdyn.load_problem(os.path.join(data, "warm_cycle_306.json"))
    second = lexdyn.load_problem(os.path.join(data, "warm_cycle_307.json"))
    options = lexdyn.load_solver_options(os.path.join(data, "warm_cycle_307.json"))
    assert options.swap_reflectors
    options.project_unit_suffix = False
    results = {}
    for swaps in (True, False):
        options.swap_reflectors = swaps
        solver = lexdyn.Solver(options)
        r1 = solver.solve(first)
        results[swaps] = solver.solve(second, warm=r1)
        assert results[swaps].status == "solved"
    assert results[True].cold_restarts == 1
    assert np.allclose(results[True].level_violation, results[False].level_violation, rtol=1e-9, atol=1e-12)


def test_a_problem_built_from_numpy_equals_the_file(problems):
    path = problems[0]
    read = lexdyn.load_problem(path, detect_bounds_level=False)
    levels = [(lv["name"], lv["A"], lv["lower"], lv["upper"]) for lv in read.levels]
    assert all(isinstance(A, np.ndarray) and A.dtype == np.float64 for _, A, _, _ in levels)
    built = lexdyn.Problem(read.variables, levels)
    # A controller's dump declares its velocity-only levels' columns (docs/file-formats.md).
    declared = [(i, lv["columns"]) for i, lv in enumerate(read.levels) if lv["columns"] >= 0]
    assert declared
    for i, columns in declared:
        built.set_level_columns(i, columns)
    assert built.to_json() == read.to_json()
    assert built.detect_bounds_level()
    assert_same_bits(lexdyn.solve(built, options=lexdyn.load_solver_options(path)).x, json.loads(lexdyn_solve(path))["x"], "x")


def test_a_problem_saved_from_python_solves_as_lexdyn_solve_does(tmp_path):
    rng = np.random.default_rng(7)
    n = 12
    p = lexdyn.Problem(n)
    p.add_level(np.eye(n)[:6], -0.5 * np.ones(6), 0.5 * np.ones(6), name="box")  # single-variable rows: a bounds level
    p.add_level(rng.standard_normal((4, n)), None, rng.standard_normal(4), name="halfspaces")
    b = rng.standard_normal(5)
    p.add_level(rng.standard_normal((5, n)), b, b, name="equalities")
    p.add_level(np.eye(n), np.zeros(n), np.zeros(n), name="regularisation")
    p.validate()
    path = str(tmp_path / "random.json")
    p.save(path)
    q = lexdyn.load_problem(path)
    r = lexdyn.solve(q)
    assert r.status == "solved" and q.levels[0]["kind"] == "bounds"
    assert lexdyn.load_solver_options(path) is None  # Problem.save writes none: lexdyn-solve runs the defaults
    assert lexdyn.result_to_json(q, r, details=True, options=lexdyn.Options(),
                                 options_from="the solver's defaults") == lexdyn_solve(path, "--details")
    assert np.all(np.abs(r.x[:6]) <= 0.5)
    # Constructed but not converted, the first level stays general: the same optimum.
    assert np.allclose(lexdyn.solve(p).x, r.x, atol=1e-9)


def test_warm_start_from_the_previous_tick(problems):
    first, second = (lexdyn.load_problem(f) for f in problems)
    solver = lexdyn.Solver()
    r1 = solver.solve(first)
    cold = lexdyn.solve(second)
    m1 = r1.multipliers.copy()
    warm = solver.solve(second, warm=r1)
    assert warm.status == cold.status == "solved"
    # Each Result keeps its own multipliers: the solver's next solve does not touch them.
    assert_same_bits(r1.multipliers, m1, "multipliers")
    assert_same_bits(warm.multipliers, lexdyn.Solver().solve(second, warm=r1).multipliers, "multipliers")
    assert np.allclose(warm.level_violation, cold.level_violation, rtol=1e-6, atol=1e-9)
    assert np.allclose(warm.x, cold.x, rtol=1e-6, atol=1e-8)
    assert warm.iterations <= cold.iterations
    # A warm start given as (active set, x) is the same as one given as the Result.
    with pytest.raises(ValueError, match="warm: a start of 1 variables"):
        lexdyn.Solver().solve(second, warm=(r1.active, np.zeros(1)))
    again = lexdyn.Solver().solve(second, warm=(r1.active, r1.x))
    assert_same_bits(again.x, warm.x, "x")
    assert [a.tolist() for a in again.active] == [a.tolist() for a in warm.active]


def test_freed_results_lend_their_buffers_to_the_next_solve(problems):
    """A freed Result gives its buffers back to its solver, whose next solve computes into them (no
    copy): every result equals a new solver's bit for bit, also when the buffers given back are of
    another problem's shape, and a Result still held is never written by a later solve."""
    first, second = (lexdyn.load_problem(f) for f in problems)
    small = lexdyn.Problem(3)
    small.add_level(np.eye(3), np.zeros(3), np.ones(3), name="box")

    def fields(r):
        return [r.status, r.x, r.level_violation, r.multipliers, [a.tolist() for a in r.active], r.rank, r.iterations]

    def assert_same(a, b, what):
        fa, fb = fields(a), fields(b)
        assert fa[0] == fb[0] and fa[4] == fb[4] and fa[5] == fb[5] and fa[6] == fb[6], what
        for x, y, name in zip(fa[1:4], fb[1:4], ("x", "level_violation", "multipliers")):
            assert_same_bits(x, y, f"{what}: {name}")

    solver = lexdyn.Solver()
    held = solver.solve(first)
    held_fields = [np.copy(f) if isinstance(f, np.ndarray) else f for f in fields(held)]
    r = None
    for k in range(8):
        p = (first, second)[k % 2]
        r = solver.solve(p)  # the previous r, freed here, lends its buffers to this solve
        assert_same(r, lexdyn.Solver().solve(p), f"cold solve {k}")
        warm = solver.solve(p, warm=r)
        assert_same(warm, lexdyn.Solver().solve(p, warm=r), f"warm solve {k}")
        assert 0.0 < r.solve_us < 1e7 and 0.0 < warm.solve_us < 1e7
        del warm
        if k == 3:
            # Buffers of a 3-variable problem's results given back: the next solves reshape them.
            solver.setup(small)
            del r
            r = [solver.solve(small) for _ in range(3)]
            del r
            r = None
            solver.setup(first)
    for a, b in zip(fields(held), held_fields):
        if isinstance(b, np.ndarray):
            assert_same_bits(a, b, "a held result")
        else:
            assert a == b
    # A refused input computes into recycled buffers too: none of an earlier result's figures
    # shows in it.
    read = lexdyn.load_problem(problems[0], detect_bounds_level=False)
    levels = [(lv["name"], lv["A"], lv["lower"], lv["upper"].copy()) for lv in read.levels]
    levels[-1][3][0] = np.nan
    bad = lexdyn.Problem(read.variables, levels)
    assert bad.detect_bounds_level()
    for _ in range(3):
        solver.solve(first)  # freed at once: its buffers go to the next solve
        refused = solver.solve(bad)
        assert refused.status == "non_finite_input"
        assert refused.bad_level == bad.level_count - 1 and refused.bad_row == 0
        assert not refused.x.any() and not refused.multipliers.any() and not refused.level_violation.any()
        assert not any(a.any() for a in refused.active)
        assert refused.iterations == 0 and refused.optimal_through == -1


def test_the_overhead_benchmark_runs(problems):
    """harness/scripts/bench_python_solve.py (docs/performance.md, "Python") on the two dumped
    ticks, one pair of one repeat: it runs both sides and prints its four overheads (the figures
    themselves are the benchmark's, never checked here)."""
    script = os.path.join(ROOT, "harness", "scripts", "bench_python_solve.py")
    binary_dir = os.path.dirname(tool("lexdyn-solve"))
    p = subprocess.run([sys.executable, script, "--pairs", "1", "--repeats", "1", "--bin", binary_dir, *problems],
                       capture_output=True, text=True, env=dict(os.environ))
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    for name in ("cold", "warm", "cold in-process", "warm in-process"):
        assert any(line.startswith(f"{name} overhead: median ") for line in lines), p.stdout
    bad = subprocess.run([sys.executable, script, "--pairs", "0", *problems], capture_output=True, text=True)
    assert bad.returncode == 2 and "--pairs" in bad.stderr


def test_options_and_errors(problems, tmp_path):
    problem = lexdyn.load_problem(problems[0])
    capped = lexdyn.solve(problem, options=lexdyn.Options(max_iterations=1, compute_multipliers=False))
    assert capped.iterations <= 1
    paper = lexdyn.Options.paper(0.005)
    assert paper.stop_total_iterations == 30 and paper.stop_optimality_iterations == 10
    with pytest.raises(ValueError, match="unknown field"):
        lexdyn.Options(max_iteration=3)
    with pytest.raises(lexdyn.InputError, match="max_iterations"):
        lexdyn.Solver(lexdyn.Options(max_iterations=0))
    bad = tmp_path / "bad.json"
    bad.write_text('{"variables": 2, "levels": [{"name": "a", "A": [[1, 2]], "lower": [1], "upper": [0]}]}')
    with pytest.raises(lexdyn.InputError, match="bad.json"):
        lexdyn.load_problem(str(bad))
    with pytest.raises(ValueError, match="columns"):
        lexdyn.Problem(3).add_level(np.ones((2, 2)), None, None)
    solver = lexdyn.Solver()
    solver.solve(problem)
    with pytest.raises(lexdyn.InputError, match="setup"):
        solver.solve(lexdyn.Problem(2, [(np.eye(2), None, None)]))


# ------------------------------------------------------------------ model
def test_hrp2kai_like_at_the_neutral_configuration(hrp2):
    assert hrp2.has_free_flyer and hrp2.nv == 6 + hrp2.num_joints and hrp2.nq == 7 + hrp2.num_joints
    q0 = hrp2.neutral()
    assert_same_bits(q0[:7], [0, 0, 0, 1, 0, 0, 0], "base of neutral()")
    hrp2.update(q0)
    com = hrp2.com()
    M = hrp2.mass_matrix()
    assert com.shape == (3,) and np.all(np.isfinite(com))
    assert M.shape == (hrp2.nv, hrp2.nv) and np.all(np.isfinite(M))
    assert np.allclose(M, M.T, rtol=0, atol=1e-12 * np.abs(M).max())
    assert np.linalg.eigvalsh(0.5 * (M + M.T)).min() > 0
    # The linear block of the free-flyer is the total mass.
    assert np.allclose(M[3:6, 3:6], hrp2.total_mass * np.eye(3), rtol=1e-12)
    # Gravity is all N at rest: the weight on the base's z row.
    assert np.isclose(hrp2.nonlinear_effects()[5], -hrp2.total_mass * hrp2.gravity[2], rtol=1e-12)


def fd_jacobian(model, q, position, h=1e-6):
    """Central differences of position(model) along each column of u (q "+" h e_i)."""
    cols = []
    for i in range(model.nv):
        e = np.zeros(model.nv)
        e[i] = h
        model.update(model.integrate(q, e, 1.0))
        plus = position(model)
        model.update(model.integrate(q, -e, 1.0))
        minus = position(model)
        cols.append((plus - minus) / (2 * h))
    model.update(q)
    return np.column_stack(cols)


def test_jacobians_match_finite_differences(hrp2):
    rng = np.random.default_rng(3)
    q = hrp2.posture("half_sitting")
    q[:3] = [0.1, -0.2, 0.6]
    axis = rng.standard_normal(3)
    axis /= np.linalg.norm(axis)
    q[3], q[4:7] = np.cos(0.15), np.sin(0.15) * axis  # a turned base
    hrp2.update(q, rng.standard_normal(hrp2.nv))
    frame = "RLEG_LINK5" if "RLEG_LINK5" in hrp2.frame_names else hrp2.frame_names[-1]
    point = np.array([0.03, -0.02, -0.1])
    J = hrp2.point_jacobian(frame, point)
    assert J.shape == (3, hrp2.nv)
    assert np.allclose(hrp2.frame_jacobian(frame)[:3], hrp2.point_jacobian(frame), atol=1e-14)
    Jfd = fd_jacobian(hrp2, q, lambda m: m.point_position(frame, point))
    assert np.allclose(J, Jfd, atol=1e-7), np.abs(J - Jfd).max()
    Jc = hrp2.com_jacobian()
    Jcfd = fd_jacobian(hrp2, q, lambda m: m.com())
    assert np.allclose(Jc, Jcfd, atol=1e-7), np.abs(Jc - Jcfd).max()
    # J u is the velocity of the point (update kept u).
    hrp2.update(q, np.linspace(-1, 1, hrp2.nv))
    assert np.allclose(hrp2.point_jacobian(frame, point) @ hrp2.u, hrp2.point_velocity(frame, point), atol=1e-12)
    assert np.allclose(hrp2.com_jacobian() @ hrp2.u, hrp2.com_velocity(), atol=1e-12)
    assert hrp2.frame_id(frame) == hrp2.frame_names.index(frame)
    with pytest.raises(lexdyn.InputError):
        hrp2.frame_id("no_such_frame")
    with pytest.raises(ValueError, match="q: expected"):
        hrp2.update(np.zeros(3))


# ------------------------------------------------------------------ case runs
def fixture_overrides(summary):
    """The --set overrides of a fixture run (without --duration and --method), in order."""
    return {o["path"]: o["value"] for o in summary["overrides"] if o["path"] not in ("stop_at_s", "controller.method")}


def test_run_case_equals_the_harness_run(outputs, tmp_path):
    ref = lexdyn.read_summary(os.path.join(outputs, GN))
    ref_trace = lexdyn.read_trace(os.path.join(outputs, GN, "trace.csv"))
    out = tmp_path / "gn"
    run = lexdyn.run_case(POINTMASS, method="gn", duration=2, overrides=fixture_overrides(ref), out_dir=str(out))
    assert run.out_dir == str(out) and os.path.isfile(out / "summary.json") and os.path.isfile(out / "case.yaml")
    tr = run.trace
    assert tr.names == ref_trace.names and tr.rows == ref_trace.rows == 401
    clock = [n for n in tr.names if n.startswith("time.")]
    assert clock, "the trace has wall-clock channels"
    for name in tr.names:
        if name not in clock:
            assert_same_bits(tr[name], ref_trace[name], name)
    assert tr.end_status == ref_trace.end_status == "completed"
    assert tr.metadata == ref_trace.metadata
    s = run.summary
    assert (s.status, s.exit_code, s.passed) == (ref.status, ref.exit_code, ref.passed) == ("completed", 0, True)
    assert s["overrides"] == ref["overrides"]
    assert [(c.name, c.passed, c.get("decides", True)) for c in s.checks] == \
        [(c.name, c.passed, c.get("decides", True)) for c in ref.checks]
    for mine, theirs in zip(s.checks, ref.checks):
        if mine.get("type") != "tick_time":
            assert mine == theirs
    assert [c.name for c in s.info_checks] == ["tick_time_p99"]
    # Everything else as the harness wrote it, but for the wall-clock figures.
    clock_keys = {"checks", "timing_us", "wall_s", "realtime_factor"}
    assert {k: v for k, v in s.items() if k not in clock_keys} == {k: v for k, v in ref.items() if k not in clock_keys}


def test_run_case_into_a_temporary_directory(outputs):
    before = set(glob.glob(os.path.join(os.environ.get("TMPDIR", "/tmp"), "lexdyn-run-*")))
    run = lexdyn.run_case(POINTMASS, method="wls", duration=2)
    assert run.out_dir is None and not os.path.exists(run.trace.path)
    assert set(glob.glob(os.path.join(os.environ.get("TMPDIR", "/tmp"), "lexdyn-run-*"))) == before
    ref = lexdyn.read_trace(os.path.join(outputs, "runs/pointmass-damping.wls", "trace.csv"))
    assert_same_bits(run.trace["q.x"], ref["q.x"], "q.x")
    # wls without overrides: the case's expected failure is not reached in 2 s, and nothing fails.
    assert run.summary.status == "completed" and run.exit_code == lexdyn.read_summary(
        os.path.join(outputs, "runs/pointmass-damping.wls")).exit_code


def test_run_case_overrides_and_bad_input(tmp_path):
    run = lexdyn.run_case(POINTMASS, duration=0.5, overrides={"controller.params.damping": 0.25, "trace.every_n_ticks": 2},
                          out_dir=str(tmp_path / "o"))
    assert [(o["path"], o["value"]) for o in run.summary["overrides"]] == [
        ("stop_at_s", "0.5"), ("controller.params.damping", "0.25"), ("trace.every_n_ticks", "2")]
    assert run.trace.rows == 51
    # Values from numpy (a DataFrame's cells) are numbers like Python's.
    run = lexdyn.run_case(POINTMASS, duration=0.5, out_dir=str(tmp_path / "np"),
                          overrides={"controller.params.damping": np.float32(0.25), "trace.every_n_ticks": np.int64(2)})
    assert [(o["path"], o["value"]) for o in run.summary["overrides"]] == [
        ("stop_at_s", "0.5"), ("controller.params.damping", "0.25"), ("trace.every_n_ticks", "2")]
    with pytest.raises(lexdyn.InputError, match="nope"):
        lexdyn.run_case(POINTMASS, overrides={"controller.nope": 1}, out_dir=str(tmp_path / "bad"))
    with pytest.raises(lexdyn.InputError, match="method"):
        lexdyn.run_case(POINTMASS, method="newton", out_dir=str(tmp_path / "bad2"))


def test_a_run_releases_the_gil():
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.005)

    t = threading.Thread(target=count)
    t.start()
    try:
        start = time.monotonic()
        lexdyn.run_case(POINTMASS, method="gn", duration=5)
        end = time.monotonic()
    finally:
        stop.set()
        t.join()
    during = [x for x in ticks if start < x < end]
    assert end - start < 0.05 or len(during) >= 3, (end - start, len(during))


INTERRUPTED_RUN = r"""
import signal, sys, lexdyn
signal.signal(signal.SIGINT, signal.default_int_handler)  # also when started with SIGINT ignored
print("running", flush=True)
try:
    lexdyn.run_case(sys.argv[1], method="gn", overrides={"duration_s": 1000}, out_dir=sys.argv[2])
except KeyboardInterrupt:
    print("KeyboardInterrupt", flush=True)
"""


def test_ctrl_c_stops_a_run_after_its_tick(tmp_path):
    out = tmp_path / "run"
    p = subprocess.Popen([sys.executable, "-c", INTERRUPTED_RUN, POINTMASS, str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "running"
        time.sleep(0.5)
        p.send_signal(signal.SIGINT)
        rest, _ = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    assert rest.strip() == "KeyboardInterrupt" and p.returncode == 0
    s = lexdyn.read_summary(str(out))
    tr = lexdyn.read_trace(str(out / "trace.csv"))
    assert s.status == "interrupted" and tr.end_status == "interrupted" and "SIGINT" in tr.end_message
    assert 0 < tr.t[-1] < 1000
