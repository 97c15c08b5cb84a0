#!/usr/bin/python3
"""plot_traces.py's second-order figure: drawn from the level.<L>.second_order_ratio and
.curvature_ratio channels, one panel per level that was ever augmented, nothing without them."""
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
SCRIPT = os.path.join(ROOT, "harness", "scripts", "plot_traces.py")
sys.path.insert(0, os.path.join(ROOT, "harness", "scripts"))

import plot_traces  # noqa: E402


def write_trace(path, levels_augmented):
    cols = ["t", "task.right_hand.error", "task.left_hand.error", "cmd.qd.J0", "cmd.tau.J0",
            "level.hands.augmented", "level.hands.second_order_ratio", "level.hands.curvature_ratio",
            "level.posture.augmented", "level.posture.second_order_ratio", "level.posture.curvature_ratio"]
    with open(path, "w") as f:
        f.write("# a comment line\n" + ",".join(cols) + "\n")
        for k in range(50):
            on = levels_augmented and k >= 20
            ratio = f"{2.5e-4 + 1e-6 * k:.9g}" if on else "nan"
            curv = f"{3e-5:.9g}" if on else "nan"
            f.write(",".join([f"{0.005 * k:.3f}", "0.5", "0.5", "0.1", "1.0", "1" if on else "0", ratio, curv,
                              "0", "nan", "nan"]) + "\n")


class SecondOrderFigure(unittest.TestCase):
    def test_figure_from_the_ratio_channels(self):
        with tempfile.TemporaryDirectory() as d:
            trace = os.path.join(d, "trace.csv")
            write_trace(trace, True)
            tr = plot_traces.Trace("bfgs", trace)
            plot_traces.plot_second_order([tr], d, "t")
            png = os.path.join(d, "second_order.png")
            self.assertTrue(os.path.isfile(png))
            with open(png, "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")

    def test_no_figure_without_augmentation(self):
        with tempfile.TemporaryDirectory() as d:
            trace = os.path.join(d, "trace.csv")
            write_trace(trace, False)
            plot_traces.plot_second_order([plot_traces.Trace("gn", trace)], d, "t")
            self.assertFalse(os.path.exists(os.path.join(d, "second_order.png")))

    def test_command_line_writes_it(self):
        with tempfile.TemporaryDirectory() as d:
            trace = os.path.join(d, "trace.csv")
            write_trace(trace, True)
            r = subprocess.run(["/usr/bin/python3", SCRIPT, "--out", os.path.join(d, "fig"), f"bfgs={trace}"],
                               capture_output=True, text=True, timeout=120)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("second_order.png", r.stdout)
            self.assertTrue(os.path.isfile(os.path.join(d, "fig", "second_order.png")))
            self.assertTrue(os.path.isfile(os.path.join(d, "fig", "task_errors.png")))

    def test_figures_option(self):
        with tempfile.TemporaryDirectory() as d:
            trace = os.path.join(d, "trace.csv")
            write_trace(trace, True)
            fig = os.path.join(d, "fig")
            r = subprocess.run(["/usr/bin/python3", SCRIPT, "--out", fig, "--figures", "second_order", f"bfgs={trace}"],
                               capture_output=True, text=True, timeout=120)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertEqual(sorted(os.listdir(fig)), ["second_order.png"])
            r = subprocess.run(["/usr/bin/python3", SCRIPT, "--out", fig, "--figures", "second-order", f"bfgs={trace}"],
                               capture_output=True, text=True, timeout=120)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn("unknown figure 'second-order'", r.stderr)


if __name__ == "__main__":
    unittest.main()
