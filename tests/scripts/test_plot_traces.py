#!/usr/bin/python3
"""plot_traces.py's figures from traces the harness wrote in this ctest run (LEXDYN_TEST_OUTPUTS,
tests/python/write_outputs.sh: the point mass with LexDynBFGS, whose level is augmented on every
tick, and with WLS, which has no second-order term). The second-order figure is drawn from the
level.<L>.second_order_ratio and .curvature_ratio channels, one panel per level that was ever
augmented, nothing without them; a damaged trace is an error naming its file and line. plot_traces
and lexdyn are found through PYTHONPATH (tests/CMakeLists.txt)."""
import os
import subprocess
import tempfile
import unittest

import plot_traces

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
SCRIPT = os.path.join(ROOT, "harness", "scripts", "plot_traces.py")


def trace(method):
    base = os.environ.get("LEXDYN_TEST_OUTPUTS")
    if not base or not os.path.isdir(base):
        raise AssertionError("LEXDYN_TEST_OUTPUTS names the harness's outputs of this run (ctest fixture lexdyn_outputs)")
    return os.path.join(base, "runs", f"pointmass-damping.{method}", "trace.csv")


class SecondOrderFigure(unittest.TestCase):
    def test_figure_from_the_ratio_channels(self):
        with tempfile.TemporaryDirectory() as d:
            tr = plot_traces.Trace("bfgs", trace("bfgs"))
            self.assertTrue(tr.has("level.position.second_order_ratio"))
            plot_traces.plot_second_order([tr], d, "t")
            png = os.path.join(d, "second_order.png")
            self.assertTrue(os.path.isfile(png))
            with open(png, "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")

    def test_no_figure_without_augmentation(self):
        with tempfile.TemporaryDirectory() as d:
            tr = plot_traces.Trace("wls", trace("wls"))
            self.assertTrue([n for n in tr.header if n.endswith(".second_order_ratio")])
            plot_traces.plot_second_order([tr], d, "t")
            self.assertFalse(os.path.exists(os.path.join(d, "second_order.png")))

    def test_command_line_writes_it(self):
        with tempfile.TemporaryDirectory() as d:
            r = subprocess.run(["/usr/bin/python3", SCRIPT, "--out", os.path.join(d, "fig"), "--errors", "position",
                                f"bfgs={trace('bfgs')}", f"wls={trace('wls')}"], capture_output=True, text=True, timeout=120)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("second_order.png", r.stdout)
            for name in ("second_order.png", "task_errors.png", "joint_velocities.png", "torques.png", "timing.png"):
                self.assertTrue(os.path.isfile(os.path.join(d, "fig", name)), name)

    def test_figures_option(self):
        with tempfile.TemporaryDirectory() as d:
            fig = os.path.join(d, "fig")
            r = subprocess.run(["/usr/bin/python3", SCRIPT, "--out", fig, "--figures", "second_order", f"bfgs={trace('bfgs')}"],
                               capture_output=True, text=True, timeout=120)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertEqual(sorted(os.listdir(fig)), ["second_order.png"])
            r = subprocess.run(["/usr/bin/python3", SCRIPT, "--out", fig, "--figures", "second-order", f"bfgs={trace('bfgs')}"],
                               capture_output=True, text=True, timeout=120)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn("unknown figure 'second-order'", r.stderr)

    def test_a_damaged_trace_is_an_error_naming_the_line(self):
        with tempfile.TemporaryDirectory() as d:
            with open(trace("bfgs")) as f:
                lines = f.read().split("\n")
            k = next(i for i, l in enumerate(lines) if l and not l.startswith("#")) + 3   # the third row
            lines[k] = lines[k].replace(",", ",x", 1)
            bad = os.path.join(d, "trace.csv")
            with open(bad, "w") as f:
                f.write("\n".join(lines))
            r = subprocess.run(["/usr/bin/python3", SCRIPT, "--out", os.path.join(d, "fig"), f"bfgs={bad}"],
                               capture_output=True, text=True, timeout=120)
            self.assertEqual(r.returncode, 2, r.stderr)
            self.assertIn(f"plot_traces: {bad}:{k + 1}: ", r.stderr)
            self.assertNotIn("Traceback", r.stderr)


if __name__ == "__main__":
    unittest.main()
