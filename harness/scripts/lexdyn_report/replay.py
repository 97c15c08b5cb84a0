"""Data of the 3D replay (docs/report.md, "3D replay"): the robot's geometry from its URDF and
data file, and a run's motion decimated and quantised from its trace.

Model (one per robot, replay/model_<robot>.js): links with their visuals (box, cylinder,
sphere, STL mesh; a link without any visual is drawn as a small marker sphere), joints
(type, parent, child, origin xyz/rpy, axis) in tree order, data-file frames (name, parent,
xyz, rpy) and contact surfaces.

Motion (replay/<run>.js): every `every`-th trace row (at most MAX_FRAMES frames), each channel
stored as 16-bit integers: value = offset + scale * k, scale = (max - min) / 65000, so a value
is off by at most scale / 2 (a joint moving 2 rad over the run: 1.5e-5 rad). k = -32768 marks
a non-finite value. A channel constant over the run is stored as that constant.
"""
import base64
import math
import os
import struct
import subprocess
import tempfile
import xml.etree.ElementTree as ET

import numpy as np

from .common import ReportInputError, read_yaml

REPO_ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", ".."))

try:
    import yaml
except ImportError:  # pragma: no cover
    yaml = None

MAX_FRAMES = 1000
TARGET_FRAME_DT_S = 0.04
NAN_CODE = -32768


def _floats(text, n, where, default):
    if text is None:
        return list(default)
    try:
        v = [float(x) for x in text.split()]
    except ValueError:
        raise ReportInputError(where, f"expected {n} numbers, found '{text}'")
    if len(v) != n:
        raise ReportInputError(where, f"expected {n} numbers, found {len(v)} ('{text}')")
    return v


def _origin(el, where):
    o = el.find("origin") if el is not None else None
    if o is None:
        return [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    return _floats(o.get("xyz"), 3, where + ".origin.xyz", [0, 0, 0]), _floats(o.get("rpy"), 3, where + ".origin.rpy", [0, 0, 0])


def read_stl(path):
    """Triangles of an STL file (binary or ASCII) as a flat list of float32 vertex coordinates."""
    with open(path, "rb") as f:
        data = f.read()
    if len(data) >= 84:
        (n,) = struct.unpack_from("<I", data, 80)
        if 84 + 50 * n == len(data):
            out = np.empty((n, 9), dtype=np.float32)
            for i in range(n):
                out[i] = struct.unpack_from("<9f", data, 84 + 50 * i + 12)
            return out.reshape(-1)
    text = data.decode("ascii", errors="replace")
    verts = []
    for lineno, line in enumerate(text.splitlines(), 1):
        parts = line.split()
        if parts and parts[0] == "vertex":
            if len(parts) != 4:
                raise ReportInputError(f"{path}:{lineno}", f"expected 'vertex x y z', found '{line.strip()}'")
            verts.extend(float(x) for x in parts[1:])
    if not verts or len(verts) % 9:
        raise ReportInputError(path, "expected an STL file (binary, or ASCII with 'vertex' lines in triangles)")
    return np.array(verts, dtype=np.float32)


def _package_name(d):
    """The <name> of d/package.xml, or None."""
    try:
        with open(os.path.join(d, "package.xml"), encoding="utf-8", errors="replace") as f:
            text = f.read()
    except OSError:
        return None
    a, b = text.find("<name>"), text.find("</name>")
    return text[a + 6:b].strip() if a >= 0 and b > a else None


def _is_package(d, name):
    if not os.path.isdir(d):
        return False
    declared = _package_name(d)
    return declared == name if declared else os.path.basename(os.path.normpath(d)) == name


def _find_package(root, name, depth=4):
    if _is_package(os.path.join(root, name), name):
        return os.path.join(root, name)
    if depth == 0 or not os.path.isdir(root):
        return None
    subs = sorted(e.path for e in os.scandir(root) if e.is_dir() and not e.name.startswith("."))
    for s in subs:
        if _is_package(s, name):
            return s
    for s in subs:
        found = _find_package(s, name, depth - 1)
        if found:
            return found
    return None


def _mesh_path(filename, urdf_dir, package_paths=()):
    """The file a URDF mesh URI names, as lexdyn's loader resolves it (docs/model.md, "Meshes and
    package:// URIs"): package://NAME/PATH in the URDF's own package (a folder above it whose
    package.xml names NAME, or named NAME), then in the package path (`package_paths`, then
    $ROS_PACKAGE_PATH); file://, absolute and relative paths. For drawing only, a package:// path
    is also tried relative to the folders above the URDF (4 levels). None when not found."""
    if filename.startswith("file://"):
        filename = filename[len("file://"):]
    if filename.startswith("package://"):
        rest = filename[len("package://"):].lstrip("/").split("/", 1)
        name, rel = rest[0], rest[1] if len(rest) == 2 else ""
        d = urdf_dir
        while True:
            if _is_package(d, name) and os.path.isfile(os.path.join(d, rel)):
                return os.path.join(d, rel)
            parent = os.path.dirname(d)
            if parent == d:
                break
            d = parent
        search = list(package_paths) + [p for p in os.environ.get("ROS_PACKAGE_PATH", "").split(":") if p]
        for root in search:
            pkg = _find_package(root, name)
            if pkg and os.path.isfile(os.path.join(pkg, rel)):
                return os.path.join(pkg, rel)
        d = urdf_dir
        for _ in range(4):
            for cand in (os.path.join(d, rel), os.path.join(d, name, rel)):
                if os.path.isfile(cand):
                    return cand
            d = os.path.dirname(d)
        return None
    p = filename if os.path.isabs(filename) else os.path.join(urdf_dir, filename)
    return p if os.path.isfile(p) else None


def _harness():
    """lexdyn-harness, to convert meshes other than STL: $LEXDYN_HARNESS (set by `lexdyn-harness
    report`), else the build's."""
    for p in (os.environ.get("LEXDYN_HARNESS"), os.path.join(REPO_ROOT, "build", "bin", "lexdyn-harness")):
        if p and os.access(p, os.X_OK):
            return p
    return None


def read_mesh(path, up_axis="ignore"):
    """Triangles (float32, 9 per triangle) of a mesh: STL read here, any other format libassimp
    reads converted by `lexdyn-harness robot mesh` (its unit applied; a COLLADA file's up axis
    applied only with up_axis="file", the data file's mesh_up_axis, as lexdyn's robot tools do).
    Raises ReportInputError naming the file."""
    if path.lower().endswith(".stl"):
        return read_stl(path)
    harness = _harness()
    if harness is None:
        raise ReportInputError(path, "a mesh other than STL needs lexdyn-harness (robot mesh) to be read; build it, or set LEXDYN_HARNESS")
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "mesh.stl")
        r = subprocess.run([harness, "robot", "mesh", path, "--out", out, "--up-axis", up_axis], capture_output=True, text=True)
        if r.returncode != 0:
            raise ReportInputError(path, "cannot read the mesh: " + (r.stderr.strip().splitlines() or ["?"])[-1])
        return read_stl(out)


def load_model(urdf_path, data_path=None, package_paths=()):
    """The replay model of a robot (a dict ready for JSON); warnings in model['warnings'].
    `package_paths`: the case's robot.package_path (resolved), for package:// mesh URIs."""
    try:
        root = ET.parse(urdf_path).getroot()
    except (OSError, ET.ParseError) as e:
        raise ReportInputError(urdf_path, f"expected a readable URDF ({e})")
    urdf_dir = os.path.dirname(os.path.abspath(urdf_path))
    materials = {}
    for m in root.findall("material"):
        c = m.find("color")
        if c is not None and m.get("name"):
            materials[m.get("name")] = _floats(c.get("rgba"), 4, f"{urdf_path}: material '{m.get('name')}'.color", [0.7] * 4)
    model = {"name": root.get("name", ""), "links": {}, "joints": [], "frames": [], "surfaces": {},
             "meshes": [], "warnings": [], "floating": False, "root": None}
    mesh_index = {}  # a mesh file used by several links is stored once
    up_axis = _mesh_up_axis(data_path)
    for link in root.findall("link"):
        name = link.get("name")
        visuals = []
        for k, v in enumerate(link.findall("visual")):
            where = f"{urdf_path}: link '{name}'.visual[{k}]"
            xyz, rpy = _origin(v, where)
            g = v.find("geometry")
            if g is None or len(g) == 0:
                raise ReportInputError(where + ".geometry", "expected a box, cylinder, sphere or mesh, found none")
            shape = g[0]
            geom = None
            if shape.tag == "box":
                geom = {"type": "box", "size": _floats(shape.get("size"), 3, where + ".box.size", [0.1] * 3)}
            elif shape.tag == "cylinder":
                geom = {"type": "cylinder", "radius": float(shape.get("radius", "0.05")),
                        "length": float(shape.get("length", "0.1"))}
            elif shape.tag == "sphere":
                geom = {"type": "sphere", "radius": float(shape.get("radius", "0.05"))}
            elif shape.tag == "mesh":
                fn = shape.get("filename", "")
                p = _mesh_path(fn, urdf_dir, package_paths)
                scale = _floats(shape.get("scale"), 3, where + ".mesh.scale", [1, 1, 1])
                if p is None:
                    model["warnings"].append(f"{where}: mesh '{fn}' not found; drawn as a marker")
                else:
                    try:
                        if p not in mesh_index:
                            tri = read_mesh(p, up_axis)
                            model["meshes"].append(base64.b64encode(tri.astype("<f4").tobytes()).decode())
                            mesh_index[p] = len(model["meshes"]) - 1
                        geom = {"type": "mesh", "mesh": mesh_index[p], "scale": scale}
                    except ReportInputError as e:
                        model["warnings"].append(f"{where}: {e}; drawn as a marker")
            else:
                raise ReportInputError(where + ".geometry", f"expected a box, cylinder, sphere or mesh, found '{shape.tag}'")
            colour = None
            mat = v.find("material")
            if mat is not None:
                c = mat.find("color")
                if c is not None:
                    colour = _floats(c.get("rgba"), 4, where + ".material.color", [0.7] * 4)
                elif mat.get("name") in materials:
                    colour = materials[mat.get("name")]
            if geom is not None:
                visuals.append({"xyz": xyz, "rpy": rpy, "geom": geom, "rgba": colour})
        model["links"][name] = {"visuals": visuals}
    children = set()
    joints = {}
    for j in root.findall("joint"):
        name = j.get("name")
        where = f"{urdf_path}: joint '{name}'"
        parent = j.find("parent").get("link") if j.find("parent") is not None else None
        child = j.find("child").get("link") if j.find("child") is not None else None
        if parent not in model["links"] or child not in model["links"]:
            raise ReportInputError(where, f"expected parent and child links of the URDF, found '{parent}' -> '{child}'")
        xyz, rpy = _origin(j, where)
        ax = j.find("axis")
        axis = _floats(ax.get("xyz") if ax is not None else None, 3, where + ".axis", [1, 0, 0])
        lim = j.find("limit")
        effort = float(lim.get("effort")) if lim is not None and lim.get("effort") else None
        joints[child] = {"name": name, "type": j.get("type"), "parent": parent, "child": child,
                         "xyz": xyz, "rpy": rpy, "axis": axis, "effort": effort}
        children.add(child)
    roots = [l for l in model["links"] if l not in children]
    if len(roots) != 1:
        raise ReportInputError(urdf_path, f"expected one root link, found {len(roots)} ({', '.join(roots)})")
    model["root"] = roots[0]
    # Depth-first pre-order (parents before children), file order among siblings.
    order, kids = [], {}
    for j in root.findall("joint"):
        c = j.find("child").get("link")
        kids.setdefault(joints[c]["parent"], []).append(c)
    stack = [roots[0]]
    while stack:
        link = stack.pop()
        if link != roots[0]:
            order.append(joints[link])
        stack.extend(reversed(kids.get(link, [])))
    model["joints"] = order
    if data_path:
        _add_data_file(model, data_path)
    return model


def _mesh_up_axis(data_path):
    """The data file's mesh_up_axis (ignore | file); ignore without one."""
    if not data_path or yaml is None:
        return "ignore"
    v = (read_yaml(data_path, "robot data file") or {}).get("mesh_up_axis", "ignore")
    if v not in ("ignore", "file"):
        raise ReportInputError(f"{data_path}: mesh_up_axis", f"expected ignore or file, found '{v}'")
    return v


def _add_data_file(model, data_path):
    if yaml is None:
        model["warnings"].append(f"{data_path}: python3-yaml missing; data-file frames not drawn")
        return
    d = read_yaml(data_path, "robot data file")
    model["floating"] = d.get("base") == "free_flyer"
    for i, fr in enumerate(d.get("frames", []) or []):
        for key in ("name", "parent"):
            if key not in fr:
                raise ReportInputError(f"{data_path}: frames[{i}].{key}", "expected this key, found none")
        model["frames"].append({"name": fr["name"], "parent": fr["parent"],
                                "xyz": [float(x) for x in fr.get("xyz", [0, 0, 0])],
                                "rpy": [float(x) for x in fr.get("rpy", [0, 0, 0])]})
    for s in d.get("contact_surfaces", []) or []:
        model["surfaces"][s["name"]] = {"frame": s["frame"], "points": s.get("points", [])}


def _encode(values):
    """One channel: {'c': constant} or {'o': offset, 's': scale, 'd': base64 int16}."""
    v = np.asarray(values, dtype=np.float64)
    ok = np.isfinite(v)
    if not ok.any():
        return {"c": None}
    lo, hi = float(v[ok].min()), float(v[ok].max())
    # Constant to rounding (a body at rest moves by ulps): stored once, since a scale of a few ulps
    # is below what (v - offset) / scale can resolve.
    if ok.all() and hi - lo <= 1e-12 * max(1.0, abs(lo), abs(hi)):
        return {"c": 0.5 * (lo + hi)}
    offset = 0.5 * (lo + hi)
    scale = (hi - lo) / 65000.0 if hi > lo else 1.0
    k = np.full(v.shape, NAN_CODE, dtype=np.int64)
    # A finite value never takes the NaN code, whatever the rounding of (v - offset) / scale.
    k[ok] = np.clip(np.rint((v[ok] - offset) / scale), NAN_CODE + 1, 32767)
    k = k.astype("<i2")
    return {"o": offset, "s": scale, "d": base64.b64encode(k.tobytes()).decode()}


def frame_every(trace):
    if trace.rows < 2:
        return 1
    dt = float(np.median(np.diff(trace.t[: min(trace.rows, 200)]))) or 0.005
    every = max(1, int(round(TARGET_FRAME_DT_S / dt)))
    return max(every, int(math.ceil(trace.rows / MAX_FRAMES)))


def replay_channels(names):
    """The channels the replay reads (a predicate for read_trace)."""
    prefixes = ("base.", "q.", "com.", "target.", "wrench.", "wrench_sensed.", "contact.", "frame.", "ctrl_contact.", "grasp.")
    return [n for n in names if n.startswith(prefixes) and not n.startswith("q_cmd.")]


def motion(run, trace, model, case_info):
    """The replay data of a run (a dict ready for JSON)."""
    every = frame_every(trace)
    idx = np.arange(0, trace.rows, every)
    if trace.rows and idx[-1] != trace.rows - 1:
        idx = np.append(idx, trace.rows - 1)  # the last state is always a frame
    channels = {}

    def add(name, values=None):
        if name in channels or (values is None and not trace.has(name)):
            return name in channels
        channels[name] = _encode(trace.col(name)[idx] if values is None else values)
        return True

    add("t")
    base = ["base.x", "base.y", "base.z", "base.rx", "base.ry", "base.rz"]
    has_base = all(add(c) for c in base)
    joints = []
    for jn in model["joints"]:
        if jn["type"] in ("revolute", "continuous", "prismatic"):
            if add(f"q.{jn['name']}"):
                joints.append(jn["name"])
    for c in ("com.x", "com.y", "com.z"):
        add(c)
    targets, box = [], None
    for n in trace.names:
        if n.startswith("target.") and n.endswith(".x"):
            task = n[len("target."):-2]
            if all(trace.has(f"target.{task}.{a}") for a in "xyz"):
                for a in "xyz":
                    add(f"target.{task}.{a}")
                t = case_info.tasks.get(task, {})
                frame = t.get("frame") if t.get("type") == "position" else None
                kind = "com" if t.get("type") == "com" else "point"
                targets.append({"task": task, "frame": frame, "kind": kind})
        if n.startswith("target.") and n.endswith(".lower_x") and box is None:
            task = n[len("target."):-len(".lower_x")]
            keys = [f"target.{task}.{s}_{a}" for s in ("lower", "upper") for a in "xyz"]
            if all(trace.has(k) for k in keys):
                box = {"task": task}
                # Open sides (+-inf) are drawn at the ground and above the robot's CoM.
                com_z = trace.col("com.z")[idx] if trace.has("com.z") else np.zeros(len(idx))
                for k in keys:
                    v = trace.col(k)[idx].copy()
                    axis, upper = k[-1], ".upper_" in k
                    if axis == "z":
                        fill = (float(np.nanmax(com_z)) + 0.4) if upper else 0.0
                    else:
                        fill = 1.5 if upper else -1.5
                    v[~np.isfinite(v)] = fill
                    add(k, v)
    contacts = []
    for n in trace.names:
        if n.startswith("ctrl_contact.") and n.endswith(".active"):
            c = n[len("ctrl_contact."):-len(".active")]
            add(n)
            spec = case_info.contacts.get(c, {})
            frame = spec.get("frame")
            if not frame and spec.get("surface") in model["surfaces"]:
                frame = model["surfaces"][spec["surface"]]["frame"]
            entry = {"name": c, "frame": frame, "active": n, "computed": None, "sensed": None}
            for kind, prefix in (("computed", "wrench."), ("sensed", "wrench_sensed.")):
                keys = [f"{prefix}{c}.{k}" for k in ("fx", "fy", "fz", "tx", "ty", "tz")]
                if all(trace.has(k) for k in keys):
                    for k in keys:
                        add(k)
                    entry[kind] = keys
            contacts.append(entry)
    surfaces = []
    if not contacts:
        # A run without the controller's contacts: the simulator's vertical contact force of
        # each surface, drawn at the centre of its touching points.
        for s in model["surfaces"]:
            fz = f"contact.{s}.fz"
            pts = []
            i = 0
            while trace.has(f"contact.{s}.p{i}.x") and trace.has(f"contact.{s}.p{i}.y"):
                pts.append([f"contact.{s}.p{i}.x", f"contact.{s}.p{i}.y"])
                i += 1
            if trace.has(fz) and pts:
                add(fz)
                for p in pts:
                    add(p[0])
                    add(p[1])
                surfaces.append({"name": s, "fz": fz, "points": pts})
    frames = [n[len("frame."):-2] for n in trace.names if n.startswith("frame.") and n.endswith(".x")]
    return {"id": run.id, "case": run.case, "method": run.method, "model": model["name"],
            "frames": int(len(idx)), "every": int(every), "rows": int(trace.rows),
            "base": base if has_base else None, "joints": joints, "targets": targets, "box": box,
            "contacts": contacts, "surfaces": surfaces, "traced_frames": frames, "channels": channels}
