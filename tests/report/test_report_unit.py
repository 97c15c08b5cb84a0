#!/usr/bin/python3
"""Unit tests of the nightly report's parts (harness/scripts/lexdyn_report; docs/report.md):
noise bands and "since last night", the history file (date order, skipped lines, damaged
figures, the lock line), the replay model and its quantisation, the sweep section and the run
verdicts rendered from files the harness wrote in this ctest run (LEXDYN_TEST_OUTPUTS: the
fixture lexdyn_outputs of tests/python/write_outputs.sh). ctest: report.unit (label report);
lexdyn and lexdyn_report are found through PYTHONPATH (tests/CMakeLists.txt)."""
import base64
import datetime
import json
import math
import os
import shutil
import struct
import subprocess
import tempfile
import unittest

import numpy as np

from lexdyn import FormatError
from lexdyn_report import history as hist
from lexdyn_report import locks, page, replay, runs, sweeps
from lexdyn_report.common import DAMAGED, DamagedNumber, ReportInputError, fnum, fpercent

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))


def outputs(*parts):
    """A file the harness wrote in this ctest run (tests/python/write_outputs.sh)."""
    base = os.environ.get("LEXDYN_TEST_OUTPUTS")
    if not base or not os.path.isdir(base):
        raise AssertionError("LEXDYN_TEST_OUTPUTS names the harness's outputs of this run (ctest fixture lexdyn_outputs)")
    return os.path.join(base, *parts)


def metric(key):
    return next(m for m in hist.METRICS if m.key == key)


def day(i):
    """The date of the i-th night of a test history (ISO-8601, UTC)."""
    return (datetime.datetime(2026, 1, 1, 2, 30, tzinfo=datetime.timezone.utc) + datetime.timedelta(days=i)).strftime("%Y-%m-%dT%H:%M:%SZ")


def record(night, run_figures, goldens_failed=None, i=0):
    rec = {"format": hist.FORMAT, "night": night, "commit": "c" + night, "date": day(i), "runs": run_figures}
    if goldens_failed is not None:
        rec["goldens"] = {"total": 3, "failed": goldens_failed}
    return rec


class NoiseBand(unittest.TestCase):
    def flag(self, key, prior, value):
        recs = [record(f"n{i}", {"r": {key: v, "failed_checks": []}}, i=i) for i, v in enumerate(prior)]
        cur = record("now", {"r": {key: value, "failed_checks": []}}, i=len(prior))
        return hist.trend(recs, cur)["r"][key]

    def test_deterministic_figure_flags_any_change(self):
        self.assertIsNone(self.flag("final_error", [2.2844] * 5, 2.2844)["flag"])
        self.assertEqual(self.flag("final_error", [2.2844] * 5, 2.2845)["flag"], "worse")
        self.assertEqual(self.flag("final_error", [2.2844] * 5, 2.2843)["flag"], "better")
        self.assertEqual(self.flag("peak_iterations", [23] * 3, 24)["flag"], "worse")
        self.assertIsNone(self.flag("peak_iterations", [23] * 3, 23)["flag"])

    def test_spread_of_earlier_nights_widens_the_band(self):
        # median 1.0, MAD 0.05: half width 3 * 1.4826 * 0.05 = 0.2224
        d = self.flag("final_error", [1.0, 1.1, 0.9, 1.05, 0.95], 1.2)
        self.assertIsNone(d["flag"])
        self.assertAlmostEqual(d["band"][1], 1.0 + 3 * 1.4826 * 0.05, places=12)
        self.assertEqual(self.flag("final_error", [1.0, 1.1, 0.9, 1.05, 0.95], 1.25)["flag"], "worse")

    def test_wall_clock_figures_use_a_factor_on_a_log_scale(self):
        d = self.flag("tick_p50_us", [300, 310, 320], 400)
        self.assertIsNone(d["flag"])
        self.assertAlmostEqual(d["band"][0], 310 / 1.5, places=9)
        self.assertAlmostEqual(d["band"][1], 310 * 1.5, places=9)
        self.assertEqual(self.flag("tick_p50_us", [300, 310, 320], 470)["flag"], "worse")
        self.assertEqual(self.flag("tick_p50_us", [300, 310, 320], 200)["flag"], "better")
        # A lower real-time factor is worse.
        self.assertEqual(self.flag("realtime_factor", [2.0, 2.0, 2.0], 0.6)["flag"], "worse")
        self.assertEqual(self.flag("realtime_factor", [2.0, 2.0, 2.0], 6.5)["flag"], "better")
        self.assertIsNone(self.flag("realtime_factor", [2.0, 2.0, 2.0], 0.7)["flag"])

    def test_no_earlier_night_no_band(self):
        d = self.flag("final_error", [], 1.0)
        self.assertIsNone(d["band"])
        self.assertIsNone(d["flag"])
        self.assertEqual([v for _, _, v in d["values"]], [1.0])

    def test_the_window_keeps_the_last_nights(self):
        prior = [5.0] * 20 + [1.0] * hist.WINDOW
        self.assertIsNone(self.flag("final_error", prior, 1.0)["flag"])

    def test_failed_check_count(self):
        recs = [record("a", {"r": {"failed_checks": []}}, i=0)]
        cur = record("b", {"r": {"failed_checks": ["x", "y"]}}, i=1)
        self.assertEqual(hist.trend(recs, cur)["r"]["failed_check_count"]["flag"], "worse")

    def test_only_nights_dated_before_count_and_damaged_figures_are_no_points(self):
        # Nights after this one (a rebuilt older night) are not its past; a NaN of an earlier
        # night is no point of the series, and this night's NaN is "damaged", not a value.
        recs = [record("n0", {"r": {"final_error": 1.0}}, i=0),
                record("n1", {"r": {"final_error": DamagedNumber("NaN")}}, i=1),
                record("n3", {"r": {"final_error": 9.0}}, i=3)]
        d = hist.trend(recs, record("n2", {"r": {"final_error": 1.0}}, i=2))["r"]["final_error"]
        self.assertEqual([(n, v) for n, _, v in d["values"]], [("n0", 1.0), ("n2", 1.0)])
        self.assertIsNone(d["flag"])
        d = hist.trend(recs, record("n2", {"r": {"final_error": DamagedNumber("Infinity")}}, i=2))["r"]["final_error"]
        self.assertTrue(d["damaged"])
        self.assertIsNone(d["value"])
        self.assertEqual([n for n, _, _ in d["values"]], ["n0"])


class SinceLastNight(unittest.TestCase):
    def test_new_failures_fixed_status_goldens_added_missing(self):
        prev = record("n1", {"exp1.bfgs": {"status": "completed", "failed_checks": ["a", "c"]},
                             "exp1.wls": {"status": "completed", "failed_checks": []},
                             "exp2.gn": {"status": "completed", "failed_checks": []}}, goldens_failed=["exp3.ah"], i=1)
        cur = record("n2", {"exp1.bfgs": {"status": "completed", "failed_checks": ["b", "c"]},
                            "exp1.wls": {"status": "controller_failure", "failed_checks": []},
                            "exp1.gn": {"status": "completed", "failed_checks": []}}, goldens_failed=["exp1.bfgs", "exp3.ah"], i=2)
        ch = hist.changes([record("n0", {}, i=0), prev], cur)
        self.assertEqual(ch["previous"]["night"], "n1")
        self.assertEqual(ch["new_failures"], [("exp1.bfgs", "b")])
        self.assertEqual(ch["fixed"], [("exp1.bfgs", "a")])
        self.assertEqual(ch["still_failing"], [("exp1.bfgs", "c")])
        self.assertEqual(ch["status"], [("exp1.wls", "completed", "controller_failure")])
        self.assertEqual(ch["added"], ["exp1.gn"])
        self.assertEqual(ch["missing"], ["exp2.gn"])
        self.assertEqual(ch["goldens_new"], ["exp1.bfgs"])
        self.assertEqual(ch["goldens_still"], ["exp3.ah"])
        self.assertEqual(ch["goldens_fixed"], [])

    def test_the_same_night_is_not_its_own_previous(self):
        cur = record("n1", {"r": {"failed_checks": ["a"]}})
        ch = hist.changes([record("n1", {"r": {"failed_checks": []}})], cur)
        self.assertIsNone(ch["previous"])
        self.assertEqual(ch["new_failures"], [])

    def test_the_previous_night_is_the_latest_dated_before(self):
        # In file order n5, n1, n3: for n4 the previous night is n3, for n2 it is n1, for n0 none.
        recs = [record("n5", {}, i=5), record("n1", {}, i=1), record("n3", {}, i=3)]
        self.assertEqual(hist.changes(recs, record("n4", {}, i=4))["previous"]["night"], "n3")
        self.assertEqual(hist.changes(recs, record("n2", {}, i=2))["previous"]["night"], "n1")
        self.assertIsNone(hist.changes(recs, record("n0", {}, i=0))["previous"])
        # The same date: the night id decides.
        self.assertEqual(hist.changes(recs, record("n4", {}, i=3))["previous"]["night"], "n3")
        self.assertEqual(hist.changes(recs, record("n2", {}, i=3))["previous"]["night"], "n1")


class HistoryFile(unittest.TestCase):
    def write(self, path, lines, end="\n"):
        with open(path, "w") as f:
            f.write("\n".join(lines) + end)

    def test_append_replaces_the_same_night_in_date_order(self):
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "sub", "history.jsonl")
            hist.append_record(path, record("n3", {}, i=3))
            hist.append_record(path, record("n1", {}, i=1))
            hist.append_record(path, record("n2", {"r": {}}, i=2))
            hist.append_record(path, record("n1", {"r": {"final_error": 0.5}}, i=1))   # n1 rebuilt
            loaded = hist.load_history(path)
            self.assertEqual([r["night"] for r in loaded.records], ["n1", "n2", "n3"])
            self.assertEqual(loaded.records[0]["runs"], {"r": {"final_error": 0.5}})
            with open(path) as f:
                self.assertEqual([json.loads(l)["night"] for l in f], ["n1", "n2", "n3"])
            self.assertEqual(loaded.warnings, [])
            self.assertFalse([n for n in os.listdir(os.path.dirname(path)) if "partial" in n])
            # The history's lock file stays, with the line of its last holder.
            with open(path + ".lock") as f:
                self.assertRegex(f.read(), r"^pid=%d started=\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ host=\S+ command=report.py\n$" % os.getpid())

    def test_bad_lines_are_skipped_with_a_warning_and_kept(self):
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "h.jsonl")
            good = json.dumps(record("n1", {"r": {"final_error": 1.0}}, i=1))
            bad = [json.dumps(record("n2", [], i=2)),                                  # runs as a list
                   "not json at all",
                   json.dumps(dict(record("n3", {}, i=3), format="lexdyn-nightly-history/0")),
                   json.dumps(record("n4", {"r": {"failed_checks": "a"}}, i=4)),      # a string, not a list
                   json.dumps(dict(record("n5", {}, i=5), date="yesterday")),
                   good[:40]]                                                         # cut, last
            self.write(path, [good] + bad, end="")
            h = hist.load_history(path)
            self.assertEqual([r["night"] for r in h.records], ["n1"])
            self.assertEqual(len(h.warnings), 6)
            self.assertIn(f"{path}:2: runs: expected an object of runs by id, found a list", h.warnings[0])
            self.assertIn(f"{path}:3: expected one JSON record per line, found a syntax error", h.warnings[1])
            self.assertIn(f"{path}:4: format: expected 'lexdyn-nightly-history/1', found 'lexdyn-nightly-history/0'", h.warnings[2])
            self.assertIn(f"{path}:5: runs.r.failed_checks: expected a list of names, found a string", h.warnings[3])
            self.assertIn(f"{path}:6: date: expected an ISO-8601 time", h.warnings[4])
            self.assertIn(f"{path}:7: expected one JSON record per line", h.warnings[5])
            self.assertIn("the file's last line has no end: cut", h.warnings[5])
            # Appending keeps the skipped lines, as they were, after the records.
            hist.append_record(path, record("n0", {}, i=0))
            with open(path) as f:
                lines = f.read().split("\n")
            self.assertEqual(lines[2:], bad + [""])
            self.assertEqual([json.loads(l)["night"] for l in lines[:2]], ["n0", "n1"])
            # strict: the first problem is an error naming file, line and field.
            with self.assertRaises(FormatError) as e:
                hist.load_history(path, strict=True)
            self.assertIn(f"{path}:3: runs: expected an object of runs by id, found a list", str(e.exception))
            self.assertEqual((e.exception.line, e.exception.field), (3, "runs"))
            with self.assertRaises(FormatError):
                hist.append_record(path, record("n9", {}, i=9), strict=True)

    def test_damaged_figures_are_left_out_with_a_warning(self):
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "h.jsonl")
            with open(path, "w") as f:
                f.write('{"format": "%s", "night": "n1", "date": "%s", "runs": {"r": {"final_error": NaN, '
                        '"tick_p50_us": "fast", "realtime_factor": -Infinity, "mean_error": 2.0}}}\n' % (hist.FORMAT, day(1)))
            h = hist.load_history(path)
            self.assertEqual(len(h.records), 1)
            self.assertEqual([w.split(": ", 1)[1] for w in h.warnings],
                             ["runs.r.final_error: expected a finite number, found NaN: left out of the trend",
                              "runs.r.tick_p50_us: expected a finite number, found \"fast\": left out of the trend",
                              "runs.r.realtime_factor: expected a finite number, found -Infinity: left out of the trend"])
            with self.assertRaises(FormatError) as e:
                hist.load_history(path, strict=True)
            self.assertIn(f"{path}:1: runs.r.final_error: expected a finite number, found NaN", str(e.exception))
            # This night's damaged figures are written as null: the file stays JSON.
            hist.append_record(path, record("n2", {"r": {"final_error": DamagedNumber("NaN"), "mean_error": float("inf")}}, i=2))
            with open(path) as f:
                lines = f.read().splitlines()
            self.assertIn("NaN", lines[0])                      # the earlier line as it was
            last = json.loads(lines[1])
            self.assertEqual(last["runs"]["r"], {"final_error": None, "mean_error": None})

    def test_no_file_and_a_folder(self):
        with tempfile.TemporaryDirectory() as d:
            self.assertEqual(hist.load_history(os.path.join(d, "none.jsonl")).records, [])
            with self.assertRaises(FormatError):
                hist.load_history(d)


class Numbers(unittest.TestCase):
    def test_damaged_figures_never_show_as_nan(self):
        n = DamagedNumber("NaN")
        self.assertTrue(math.isnan(n))
        for text in (fnum(n), fnum(float("nan")), fnum(float("inf"), ".0f"), fnum("fast"), str(n), f"{n:.3f}", fpercent(n)):
            self.assertEqual(text, DAMAGED)
        self.assertEqual(fnum(None), "-")
        self.assertEqual(fnum(2.5, ".1f"), "2.5")
        self.assertEqual(fpercent(0.75), "75.0 %")
        self.assertEqual(fpercent(None), "-")


class LockLine(unittest.TestCase):
    def test_holder_line_and_its_description(self):
        line = locks.holder_line("report.py")
        self.assertRegex(line, r"^pid=%d started=\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ host=\S+ command=report.py\n$" % os.getpid())
        self.assertEqual(locks.describe_holder("pid=1234 started=2026-11-28T07:01:02Z host=vm command=lexdyn-harness run\n"),
                         "pid 1234, lexdyn-harness run, started 2026-11-28T07:01:02Z on vm")
        self.assertEqual(locks.describe_holder(""), "holder unknown")
        self.assertEqual(locks.describe_holder("\x00garbage"), "holder unknown")


class DetailTime(unittest.TestCase):
    def test_detail_time(self):
        self.assertEqual(runs.detail_time("largest sensed ratio at t = 0.82 s (f_n 318 N)"), 0.82)
        self.assertIsNone(runs.detail_time("no trace row at t >= 100.000000 s"))
        self.assertIsNone(runs.detail_time(""))


def binary_stl(triangles):
    out = b"\0" * 80 + struct.pack("<I", len(triangles))
    for tri in triangles:
        out += struct.pack("<3f", 0, 0, 1) + struct.pack("<9f", *[c for v in tri for c in v]) + b"\0\0"
    return out


class ReplayModel(unittest.TestCase):
    def test_the_humanoid(self):
        m = replay.load_model(os.path.join(ROOT, "models/hrp2kai_like/hrp2kai_like.urdf"),
                              os.path.join(ROOT, "models/hrp2kai_like/hrp2kai_like.yaml"))
        self.assertEqual(m["name"], "hrp2kai_like")
        self.assertEqual(m["root"], "WAIST")
        self.assertTrue(m["floating"])
        moving = [j for j in m["joints"] if j["type"] in ("revolute", "continuous", "prismatic")]
        self.assertEqual(len(moving), 32)
        names = [j["name"] for j in m["joints"]]
        # Parents before children.
        seen = {m["root"]}
        for j in m["joints"]:
            self.assertIn(j["parent"], seen)
            seen.add(j["child"])
        self.assertLess(names.index("RARM_JOINT0"), names.index("RARM_JOINT6"))
        grasp = next(f for f in m["frames"] if f["name"] == "RGRASP")
        self.assertEqual((grasp["parent"], grasp["xyz"]), ("RARM_LINK6", [0.0, 0.0, -0.15]))
        self.assertEqual(m["surfaces"]["LEFT_FOOT"]["frame"], "LSOLE")
        self.assertEqual(next(j for j in m["joints"] if j["name"] == "RLEG_JOINT3")["effort"], 300.0)
        self.assertEqual(m["warnings"], [])
        shapes = {v["geom"]["type"] for link in m["links"].values() for v in link["visuals"]}
        self.assertEqual(shapes, {"box", "cylinder"})

    def test_meshes_spheres_missing_files_and_bare_links(self):
        tri = [((0, 0, 0), (1, 0, 0), (0, 1, 0)), ((0, 0, 0), (0, 1, 0), (0, 0, 1))]
        with tempfile.TemporaryDirectory() as d:
            os.makedirs(os.path.join(d, "meshes"))
            with open(os.path.join(d, "meshes", "a.stl"), "wb") as f:
                f.write(binary_stl(tri))
            with open(os.path.join(d, "meshes", "b.stl"), "w") as f:
                f.write("solid b\n" + "".join("facet normal 0 0 1\nouter loop\n" + "".join(f"vertex {x} {y} {z}\n" for x, y, z in t)
                                              + "endloop\nendfacet\n" for t in tri) + "endsolid b\n")
            urdf = os.path.join(d, "r.urdf")
            with open(urdf, "w") as f:
                f.write("""<robot name="r"><material name="red"><color rgba="1 0 0 1"/></material>
  <link name="base"><visual><geometry><mesh filename="package://r/meshes/a.stl" scale="2 2 2"/></geometry>
    <material name="red"/></visual></link>
  <link name="l1"><visual><origin xyz="0 0 0.1" rpy="0 1.5707963 0"/><geometry><sphere radius="0.1"/></geometry></visual>
    <visual><geometry><mesh filename="meshes/b.stl"/></geometry></visual></link>
  <link name="l2"><visual><geometry><mesh filename="meshes/missing.dae"/></geometry></visual></link>
  <link name="l3"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="5" velocity="1"/></joint>
  <joint name="j2" type="prismatic"><parent link="l1"/><child link="l2"/><origin xyz="0.5 0 0"/></joint>
  <joint name="j3" type="fixed"><parent link="base"/><child link="l3"/></joint>
</robot>""")
            m = replay.load_model(urdf)
            self.assertEqual(m["root"], "base")
            self.assertEqual([j["name"] for j in m["joints"]], ["j1", "j2", "j3"])
            v = m["links"]["base"]["visuals"][0]
            self.assertEqual((v["geom"]["type"], v["geom"]["scale"], v["rgba"]), ("mesh", [2.0, 2.0, 2.0], [1.0, 0.0, 0.0, 1.0]))
            a = np.frombuffer(base64.b64decode(m["meshes"][0]), dtype="<f4")
            b = np.frombuffer(base64.b64decode(m["meshes"][1]), dtype="<f4")
            self.assertEqual(a.tolist(), [c for t in tri for v in t for c in v])
            self.assertEqual(a.tolist(), b.tolist())  # binary and ASCII STL read alike
            self.assertEqual(m["links"]["l1"]["visuals"][0]["geom"], {"type": "sphere", "radius": 0.1})
            self.assertEqual(m["links"]["l2"]["visuals"], [])   # drawn as a marker
            self.assertEqual(m["links"]["l3"]["visuals"], [])
            self.assertEqual(len(m["warnings"]), 1)
            self.assertIn("missing.dae", m["warnings"][0])
            self.assertEqual(m["joints"][1]["axis"], [1.0, 0.0, 0.0])  # URDF default axis

    def test_meshes_of_other_formats_and_package_paths(self):
        # An OBJ mesh (any format libassimp reads) through `lexdyn-harness robot mesh`, found as
        # package://NAME/... through a package path whose package.xml names NAME.
        self.assertTrue(os.environ.get("LEXDYN_HARNESS"), "LEXDYN_HARNESS names the harness (set by ctest)")
        with tempfile.TemporaryDirectory() as d:
            pkg = os.path.join(d, "ws", "src", "folder_of_pkg")
            os.makedirs(os.path.join(pkg, "meshes"))
            with open(os.path.join(pkg, "package.xml"), "w") as f:
                f.write("<package>\n  <name>my_pkg</name>\n</package>\n")
            with open(os.path.join(pkg, "meshes", "tri.obj"), "w") as f:
                f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\n")
            os.makedirs(os.path.join(d, "robot"))
            urdf = os.path.join(d, "robot", "r.urdf")
            with open(urdf, "w") as f:
                f.write('<robot name="r"><link name="base"><visual><geometry><mesh filename="package://my_pkg/meshes/tri.obj"/>'
                        '</geometry></visual><visual><geometry><mesh filename="package://my_pkg/meshes/tri.obj"/></geometry></visual>'
                        '</link></robot>')
            m = replay.load_model(urdf)
            self.assertEqual(m["links"]["base"]["visuals"], [])  # not found without the package path
            self.assertEqual(len(m["warnings"]), 2)
            m = replay.load_model(urdf, None, [os.path.join(d, "ws")])
            self.assertEqual(m["warnings"], [])
            self.assertEqual(len(m["meshes"]), 1)  # one file, stored once for both visuals
            tri = np.frombuffer(base64.b64decode(m["meshes"][0]), dtype="<f4").reshape(-1, 3, 3)
            self.assertEqual(tri.shape, (2, 3, 3))
            self.assertEqual(sorted(map(tuple, tri.reshape(-1, 3).tolist())),
                             sorted([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 0), (0, 1, 0), (0, 0, 1)]))
            # A file that is not a mesh: a warning naming it, drawn as a marker.
            with open(os.path.join(pkg, "meshes", "tri.obj"), "w") as f:
                f.write("not a mesh\n")
            m = replay.load_model(urdf, None, [os.path.join(d, "ws")])
            self.assertEqual(len(m["warnings"]), 2)
            self.assertIn("tri.obj: cannot read the mesh", m["warnings"][0])

    def test_a_collada_up_axis_follows_the_data_file(self):
        # A Y_UP COLLADA triangle: as written without a data file (ROS's tools' reading), turned
        # to z up ((x, y, z) -> (x, -z, y)) with the data file's mesh_up_axis: file.
        self.assertTrue(os.environ.get("LEXDYN_HARNESS"), "LEXDYN_HARNESS names the harness (set by ctest)")
        with tempfile.TemporaryDirectory() as d:
            with open(os.path.join(d, "t.dae"), "w") as f:
                f.write('<?xml version="1.0"?>\n<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">'
                        '<asset><unit meter="1"/><up_axis>Y_UP</up_axis></asset><library_geometries><geometry id="g"><mesh>'
                        '<source id="p"><float_array id="pa" count="9">0 0 0 1 0 0 0 1 0</float_array><technique_common>'
                        '<accessor source="#pa" count="3" stride="3"><param name="X" type="float"/><param name="Y" type="float"/>'
                        '<param name="Z" type="float"/></accessor></technique_common></source><vertices id="v">'
                        '<input semantic="POSITION" source="#p"/></vertices><triangles count="1"><input semantic="VERTEX" source="#v" '
                        'offset="0"/><p>0 1 2</p></triangles></mesh></geometry></library_geometries><library_visual_scenes>'
                        '<visual_scene id="s"><node id="n"><instance_geometry url="#g"/></node></visual_scene>'
                        '</library_visual_scenes><scene><instance_visual_scene url="#s"/></scene></COLLADA>\n')
            urdf = os.path.join(d, "r.urdf")
            with open(urdf, "w") as f:
                f.write('<robot name="r"><link name="base"><visual><geometry><mesh filename="t.dae"/></geometry></visual></link></robot>')
            data = os.path.join(d, "r.yaml")
            def triangle(data_path):
                m = replay.load_model(urdf, data_path)
                self.assertEqual(m["warnings"], [])
                return np.frombuffer(base64.b64decode(m["meshes"][0]), dtype="<f4").reshape(3, 3).tolist()
            written = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
            self.assertEqual(triangle(None), written)
            for up, expected in (("ignore", written), ("file", [[0, 0, 0], [1, 0, 0], [0, 0, 1]])):
                with open(data, "w") as f:
                    f.write(f"format: lexdyn-robot-data/1\nrobot: r\nbase: fixed\nmesh_up_axis: {up}\n")
                self.assertEqual(triangle(data), expected, up)
            with open(data, "w") as f:
                f.write("format: lexdyn-robot-data/1\nrobot: r\nbase: fixed\nmesh_up_axis: y\n")
            with self.assertRaises(ReportInputError) as e:
                replay.load_model(urdf, data)
            self.assertIn("r.yaml: mesh_up_axis: expected ignore or file, found 'y'", str(e.exception))

    def test_urdf_errors_name_the_file_and_element(self):
        with tempfile.TemporaryDirectory() as d:
            urdf = os.path.join(d, "r.urdf")
            with open(urdf, "w") as f:
                f.write('<robot name="r"><link name="a"><visual><geometry><box size="1 1"/></geometry></visual></link></robot>')
            with self.assertRaises(ReportInputError) as e:
                replay.load_model(urdf)
            self.assertIn("link 'a'.visual[0].box.size: expected 3 numbers, found 2", str(e.exception))
            with open(urdf, "w") as f:
                f.write('<robot name="r"><link name="a"/><link name="b"/></robot>')
            with self.assertRaises(ReportInputError) as e:
                replay.load_model(urdf)
            self.assertIn("expected one root link, found 2", str(e.exception))


class Quantisation(unittest.TestCase):
    def decode(self, ch, n):
        if "c" in ch:
            return np.full(n, np.nan if ch["c"] is None else ch["c"])
        k = np.frombuffer(base64.b64decode(ch["d"]), dtype="<i2").astype(float)
        return np.where(k == replay.NAN_CODE, np.nan, ch["o"] + ch["s"] * k)

    def test_round_trip_within_half_a_step(self):
        rng = np.random.RandomState(7)
        v = np.cumsum(rng.normal(0, 0.01, 5000)) + 0.3
        ch = replay._encode(v)
        back = self.decode(ch, len(v))
        self.assertLessEqual(np.max(np.abs(back - v)), ch["s"] / 2 * (1 + 1e-9))
        self.assertAlmostEqual(ch["s"], (v.max() - v.min()) / 65000, places=15)

    def test_values_at_rest_never_become_nan(self):
        # A base at rest moves by ulps (0.7839259367176750 +- 1e-16): a scale that small cannot
        # be resolved by (v - offset) / scale, and the rounding once gave the NaN code.
        v = 0.783925936717675 + np.array([0.0, 1.1e-16, -1.1e-16, 2.2e-16, 0.0])
        ch = replay._encode(v)
        self.assertIn("c", ch)
        self.assertAlmostEqual(ch["c"], 0.783925936717675, places=15)
        # Just above that threshold the values are quantised, and none is the NaN code.
        v = 1.0 + np.array([0.0, 3e-12, -3e-12, 1e-12])
        back = self.decode(replay._encode(v), len(v))
        self.assertTrue(np.all(np.isfinite(back)))
        self.assertLessEqual(np.max(np.abs(back - v)), 1e-15)

    def test_constants_and_non_finite_values(self):
        self.assertEqual(replay._encode([1.5, 1.5, 1.5]), {"c": 1.5})
        self.assertEqual(replay._encode([np.nan, np.inf]), {"c": None})
        ch = replay._encode([1.0, np.nan, 2.0, np.inf])
        back = self.decode(ch, 4)
        self.assertEqual(back[0], 1.0)
        self.assertEqual(back[2], 2.0)
        self.assertTrue(np.isnan(back[1]) and np.isnan(back[3]))


def real_sweep(d, name="pm-grid"):
    """A copy in D of the sweep the harness ran in this ctest run (a 2 x 2 grid of the point mass,
    wls and bfgs; tests/python/write_outputs.sh); NAME renames it. Returns its summary."""
    shutil.copytree(outputs("sweep"), d)
    path = os.path.join(d, "summary.json")
    with open(path) as f:
        summary = json.load(f)
    if name != summary["name"]:
        summary["name"] = name
        with open(path, "w") as f:
            json.dump(summary, f)
    return summary


def write_json(path, doc):
    with open(path, "w") as f:
        json.dump(doc, f)


class SweepSection(unittest.TestCase):
    def test_rendering_of_a_real_sweep(self):
        with tempfile.TemporaryDirectory() as d:
            s = real_sweep(os.path.join(d, "sweeps", "grid"), name="grid")
            real_sweep(os.path.join(d, "sweeps", "nomap"), name="nomap")
            for m in s["maps"]:
                os.unlink(os.path.join(d, "sweeps", "nomap", m["png"]))
            sws = sweeps.load_sweeps(os.path.join(d, "sweeps"))
            self.assertEqual([x.name for x in sws], ["grid", "nomap"])
            out = os.path.join(d, "report")
            assets, warnings = page.sweep_assets(sws, out)
            html = page.sweeps_section(sws, assets)
            self.assertIn("id='sweep-grid'", html)
            # A row per check and method, each with the pass rate the sweep computed.
            self.assertEqual(html.count("<tr><td>no_overshoot</td>"), 2 * 2)
            for c in s["checks"]:
                self.assertIn(fpercent(c["pass_rate"]), html)
            wls = next(c for c in s["checks"] if c["check"] == "no_overshoot" and c["method"] == "wls")
            self.assertLess(wls["pass_rate"], 1.0, "wls overshoots at damping 1, kp 2 (write_outputs.sh)")
            self.assertIn(fnum(wls["worst_margin"], ".4g"), html)
            # Every map copied beside the page; the maps of the sweep without pictures missing.
            for i, m in enumerate(s["maps"]):
                self.assertTrue(os.path.isfile(os.path.join(out, "sweeps", "grid", f"map{i}.png")))
                self.assertTrue(os.path.isfile(os.path.join(out, "sweeps", "grid", f"map{i}.csv")))
                self.assertIn(f"src='sweeps/grid/map{i}.png'", html)
            self.assertEqual(len(warnings), len(s["maps"]))
            self.assertTrue(all("png: expected an image file, found none" in w for w in warnings))
            self.assertIn("the map image is missing", html)
            # The failure and the command that reproduces it.
            f = s["failures"][0]
            self.assertEqual((f["method"], f["check"]), ("wls", "no_overshoot"))
            self.assertIn(page.esc(f["command"]), html)
            for o in f["overrides"]:
                self.assertIn(page.esc(f"{o['path']} = {o['value']}"), html)

    def test_status_counts_are_those_of_the_runs_the_sweep_recorded(self):
        """The per-method status counts come from the `runs` of each record of results.jsonl, as
        the sweep driver writes them (harness/sweep/sweep_records.cpp): a reader of another key
        (the report once read `methods`) shows no counts, and this test fails."""
        with tempfile.TemporaryDirectory() as d:
            s = real_sweep(os.path.join(d, "grid"))
            sw = sweeps.load_sweeps(os.path.join(d, "grid"))[0]
            counts = sw.method_status_counts()
            # The driver's own count of each method's runs (run_completed: runs, passed).
            for m in s["methods"]:
                done = next(c for c in s["checks"] if c["check"] == "run_completed" and c["method"] == m)
                self.assertEqual(sum(counts[m].values()), done["runs"], m)
                self.assertEqual(counts[m].get("completed", 0), done["passed"], m)
            self.assertEqual(sorted(counts), sorted(s["methods"]))
            html = page.sweeps_section([sw], page.sweep_assets([sw], os.path.join(d, "out"))[0])
            self.assertIn("results.jsonl: " + "; ".join(
                f"{m}: " + ", ".join(f"{k} {v}" for k, v in sorted(counts[m].items())) for m in sorted(counts)), html)
            # A record with the runs under another key is refused, naming the file, line and key.
            path = os.path.join(d, "grid", "results.jsonl")
            with open(path) as f:
                lines = f.read().splitlines()
            rec = json.loads(lines[1])
            rec["methods"] = rec.pop("runs")
            lines[1] = json.dumps(rec)
            with open(path, "w") as f:
                f.write("\n".join(lines) + "\n")
            with self.assertRaises(FormatError) as e:
                sweeps.load_sweeps(os.path.join(d, "grid"))
            self.assertEqual((e.exception.path, e.exception.line, e.exception.field), (path, 2, "runs"))

    def test_damaged_figures_of_a_sweep(self):
        # NaN where a sweep summary has numbers (Python's json writes and reads it): "not a
        # number (damaged)", never "nan" nor "- %"; a missing rate is "-".
        with tempfile.TemporaryDirectory() as d:
            s = real_sweep(os.path.join(d, "one"))
            s["checks"][0]["pass_rate"] = float("nan")
            s["checks"][1]["pass_rate"] = None
            s["checks"][1]["worst_margin"] = float("nan")
            s["comparisons"] = [{"name": "bfgs_vs_wls", "better": "bfgs", "worse": "wls", "points": 4, "wins": 3,
                                 "win_rate": float("inf"), "diff": {"min": -0.2, "p10": -0.15, "median": -0.05, "p90": 0.01, "max": 0.02}}]
            write_json(os.path.join(d, "one", "summary.json"), s)
            sws = sweeps.load_sweeps(os.path.join(d, "one"))
            html = page.sweeps_section(sws, page.sweep_assets(sws, os.path.join(d, "out"))[0])
            self.assertEqual(html.count(DAMAGED), 3)
            self.assertNotRegex(html, r"(?i)\bnan\b|\binf\b|- %")
            self.assertIn("<td>-</td>", html)
            rec = {"runs": {}}
            hist.add_sweeps(rec, sws)
            self.assertNotIn(f"{s['checks'][0]['check']}/{s['checks'][0]['method']}", rec["sweeps"]["pm-grid"])

    def test_one_sweep_directory_and_errors(self):
        with tempfile.TemporaryDirectory() as d:
            s = real_sweep(os.path.join(d, "one"))
            self.assertEqual(len(sweeps.load_sweeps(os.path.join(d, "one"))), 1)
            self.assertIn("no sweep results", page.sweeps_section([], {}).lower())
            path = os.path.join(d, "one", "summary.json")
            write_json(path, dict(s, format="lexdyn-sweep-summary/0"))
            with self.assertRaises(FormatError) as e:
                sweeps.load_sweeps(os.path.join(d, "one"))
            self.assertIn("summary.json: format: expected 'lexdyn-sweep-summary/1', found 'lexdyn-sweep-summary/0'", str(e.exception))
            del s["checks"][1]["pass_rate"]
            write_json(path, s)
            with self.assertRaises(FormatError) as e:
                sweeps.load_sweeps(os.path.join(d, "one"))
            self.assertIn("summary.json: checks[1].pass_rate: expected this key, found none", str(e.exception))


class RunVerdicts(unittest.TestCase):
    """The page's verdict of a run is the run's own (its exit code); a check that decides nothing
    (decides: false: the wall-clock tick_time) is shown as info, never as a failure. On the runs
    the harness wrote in this ctest run (tests/python/write_outputs.sh): pointmass-damping.gn's
    p99 tick time is above an impossible limit of 1 ns, and the run exits 0."""

    def test_a_failing_check_that_decides_nothing_is_info(self):
        run = runs.Run("pointmass-damping.gn", outputs("runs", "pointmass-damping.gn"))
        info = [c for c in run.summary["checks"] if c.get("decides") is False]
        self.assertEqual([(c["name"], c["passed"]) for c in info], [("tick_time_p99", False)])
        self.assertEqual(run.summary["exit_code"], 0)
        self.assertEqual(run.failed_checks, [])
        self.assertTrue(run.passed)
        n = len(run.summary["checks"]) - 1
        self.assertEqual(page._cls(run), "pass")
        self.assertTrue(page._verdict_text(run).startswith(f"pass ({n}/{n} checks, 1 info)"), page._verdict_text(run))
        rows = page._failing_rows(run)
        self.assertEqual(len(rows), 1)
        self.assertTrue(rows[0].startswith("<tr class='info'>"), rows[0])
        self.assertIn("tick_time_p99 (info: machine-dependent, reported only)", rows[0])
        self.assertEqual(hist.night_record(runs.Results(outputs("runs")))["runs"]["pointmass-damping.gn"]["failed_checks"], [])

    def test_the_page_agrees_with_every_run_exit_code(self):
        with open(outputs("report", "index.html")) as f:
            html = f.read()
        results = runs.Results(outputs("runs"))
        self.assertEqual(len(results.runs), 3)
        for run in results.runs:
            cell = html[html.index(f"data-run='{run.id}'"):]
            cell = cell[:cell.index("</td>")]
            code = run.summary["exit_code"]
            self.assertIn(page._cls(run), ("pass", "xfail") if code == 0 else ("fail", "stop"), run.id)
            head = cell.split(">", 1)[1]
            if code == 0:
                self.assertTrue(head.startswith(("pass (", "expected failure (")), (run.id, head))
            else:
                self.assertFalse(head.startswith(("pass (", "expected failure (")), (run.id, head))
        self.assertIn(f"{len(results.runs)} of {len(results.runs)} runs passed", html)


class ExpectedFailureVerdict(unittest.TestCase):
    """A run that fails as its case expects (summary.json "expected_failure") has its own verdict
    and colour; one that fails otherwise says so; a run without an entry is judged as before."""

    def run_with(self, d, summary):
        os.makedirs(d)
        with open(os.path.join(d, "summary.json"), "w") as f:
            json.dump(summary, f)
        return runs.Run("pm.wls", d)

    def test_verdicts(self):
        checks = [{"name": "no_overshoot", "passed": False}, {"name": "controller_ok", "passed": True}]
        base = {"case": "pm", "method": "wls", "status": "completed", "checks": checks}
        with tempfile.TemporaryDirectory() as d:
            plain = self.run_with(os.path.join(d, "a"), base)
            self.assertEqual(page._cls(plain), "fail")
            self.assertEqual(page._verdict_text(plain), "FAIL (1/2 checks)")
            met = self.run_with(os.path.join(d, "b"), dict(base, expected_failure={
                "status": "completed", "checks": ["no_overshoot"], "reason": "overshoots", "met": True, "mismatches": []}))
            self.assertTrue(met.failed_as_expected)
            self.assertEqual(page._cls(met), "xfail")
            self.assertEqual(page._verdict_text(met), "expected failure (1/2 checks)")
            stopped = self.run_with(os.path.join(d, "c"), dict(base, status="controller_failure", expected_failure={
                "status": "completed", "checks": ["no_overshoot"], "reason": "r", "met": False,
                "mismatches": ["status controller_failure (expected completed)"]}))
            self.assertFalse(stopped.failed_as_expected)
            self.assertEqual(page._cls(stopped), "stop")
            self.assertEqual(page._verdict_text(stopped), "NOT the expected failure: controller_failure (1/2 checks)")

    def test_failing_checks_rows(self):
        """In the failing-checks table a check the case expects to fail has the xfail colour, a check
        it does not list the failure colour, also when the run is otherwise as expected."""
        checks = [{"name": "no_overshoot", "passed": False}, {"name": "eq49", "passed": False},
                  {"name": "controller_ok", "passed": True}]
        base = {"case": "pm", "method": "wls", "status": "completed", "checks": checks}
        with tempfile.TemporaryDirectory() as d:
            plain = page._failing_rows(self.run_with(os.path.join(d, "a"), base))
            self.assertEqual([r.split("'")[1] for r in plain], ["fail", "fail"])
            partial = page._failing_rows(self.run_with(os.path.join(d, "b"), dict(base, expected_failure={
                "status": "completed", "checks": ["no_overshoot"], "reason": "overshoots", "met": False,
                "mismatches": ["eq49 failed (not expected)"]})))
            self.assertEqual([r.split("'")[1] for r in partial], ["fail", "xfail", "fail"])
            self.assertIn("NOT the expected failure: eq49 failed (not expected)", partial[0])
            self.assertIn(">no_overshoot<", partial[1])
            self.assertIn(">eq49<", partial[2])
            met = page._failing_rows(self.run_with(os.path.join(d, "c"), dict(base, expected_failure={
                "status": "completed", "checks": ["eq49", "no_overshoot"], "reason": "r", "met": True, "mismatches": []})))
            self.assertEqual([r.split("'")[1] for r in met], ["xfail", "xfail", "xfail"])


class CommandLine(unittest.TestCase):
    def run_report(self, *args):
        return subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "harness", "scripts", "report.py"), *args],
                              capture_output=True, text=True, timeout=120)

    def test_bad_input_is_exit_code_2_naming_what(self):
        with tempfile.TemporaryDirectory() as d:
            r = self.run_report("--runs", os.path.join(d, "nope"), "--out", os.path.join(d, "out"))
            self.assertEqual(r.returncode, 2, r.stderr)
            self.assertIn(os.path.join(d, "nope"), r.stderr)
            os.makedirs(os.path.join(d, "empty"))
            r = self.run_report("--runs", os.path.join(d, "empty"), "--out", os.path.join(d, "out"))
            self.assertEqual(r.returncode, 2)
            self.assertIn("summary.json", r.stderr)
            r = self.run_report("--runs", os.path.join(d, "empty"), "--out", os.path.join(d, "out"), "--append-history")
            self.assertEqual(r.returncode, 2)
            self.assertIn("--history", r.stderr)
            r = self.run_report("--out", os.path.join(d, "out"))
            self.assertEqual(r.returncode, 2)
            # Bad options: one line, no usage block, no traceback.
            self.assertEqual(r.stderr.strip().splitlines(), ["report: error: the following arguments are required: --runs (--help for the options)"])
            r = self.run_report("--runs", os.path.join(d, "empty"), "--out", os.path.join(d, "out"), "--strict-history")
            self.assertEqual((r.returncode, r.stderr), (2, "report: error: --strict-history: expected --history FILE as well, found none\n"))
            r = self.run_report("--runs", os.path.join(d, "empty"), "--out", os.path.join(d, "out"), "--frobnicate")
            self.assertEqual(r.returncode, 2)
            self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
            self.assertIn("--frobnicate", r.stderr)


if __name__ == "__main__":
    unittest.main(verbosity=2)
