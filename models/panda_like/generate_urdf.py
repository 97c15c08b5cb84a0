#!/usr/bin/env python3
"""Writes the panda_like_description package: a Franka-Emika-Panda-like 7-DoF arm with a
two-finger parallel gripper, in the conventions of real ROS description packages (see README.md
for every figure and its source).

    /usr/bin/python3 models/panda_like/generate_urdf.py

writes, next to this script (all deterministic: byte-identical on every run):
    package.xml                 the ROS package manifest (name panda_like_description)
    urdf/panda_like.urdf        links, joints, limits, inertias, meshes, extras
    srdf/panda_like.srdf        groups, the "ready" group_state, the hand states, end effector
    meshes/<name>.stl           small binary STL meshes (boxes and 16-facet cylinders, metres)
and prints its checks (total mass, reach, heights, joint counts, the ready posture inside the
limits, the inertia classes). Every check is an assertion.

The joint origins follow from Franka's published modified (Craig) Denavit-Hartenberg parameters:
a joint with (a, d, alpha) has the URDF origin rpy = (alpha, 0, 0), xyz = (a, -sin(alpha) d,
cos(alpha) d). The link masses, centres of mass and inertias of links 1-7 are the published
identification of Gaz et al. (2019). Pure Python, no numpy.
"""
import hashlib
import math
import os
import struct
import sys

ROBOT = "panda_like"
PKG = "panda_like_description"
HERE = os.path.dirname(os.path.abspath(__file__))
HALF_PI = math.pi / 2

# Modified DH (Craig): joint, a (m), d (m), alpha (rad). Franka, "Robot and interface specifications".
DH = [
    ("panda_joint1", 0.0, 0.333, 0.0),
    ("panda_joint2", 0.0, 0.0, -HALF_PI),
    ("panda_joint3", 0.0, 0.316, HALF_PI),
    ("panda_joint4", 0.0825, 0.0, HALF_PI),
    ("panda_joint5", -0.0825, 0.384, -HALF_PI),
    ("panda_joint6", 0.0, 0.0, HALF_PI),
    ("panda_joint7", 0.088, 0.0, HALF_PI),
    ("panda_joint8", 0.0, 0.107, 0.0),  # the flange (fixed)
]
# Limits: lower, upper (rad), velocity (rad/s), effort (Nm). Franka, "Limits for Panda".
LIMITS = {
    "panda_joint1": (-2.8973, 2.8973, 2.175, 87.0),
    "panda_joint2": (-1.7628, 1.7628, 2.175, 87.0),
    "panda_joint3": (-2.8973, 2.8973, 2.175, 87.0),
    "panda_joint4": (-3.0718, -0.0698, 2.175, 87.0),
    "panda_joint5": (-2.8973, 2.8973, 2.61, 12.0),
    "panda_joint6": (-0.0175, 3.7525, 2.61, 12.0),
    "panda_joint7": (-2.8973, 2.8973, 2.61, 12.0),
}
# Links 1-7: mass (kg), CoM (m, link frame), inertia about the CoM (ixx, ixy, ixz, iyy, iyz, izz).
# Gaz et al. 2019, supplementary material, tables VIII and IX (feasible retrieved parameters).
GAZ = {
    "panda_link1": (4.970684, (3.875e-03, 2.081e-03, 0.0), (7.0337e-01, -1.3900e-04, 6.7720e-03, 7.0661e-01, 1.9169e-02, 9.1170e-03)),
    "panda_link2": (0.646926, (-3.141e-03, -2.872e-02, 3.495e-03), (7.9620e-03, -3.9250e-03, 1.0254e-02, 2.8110e-02, 7.0400e-04, 2.5995e-02)),
    "panda_link3": (3.228604, (2.7518e-02, 3.9252e-02, -6.6502e-02), (3.7242e-02, -4.7610e-03, -1.1396e-02, 3.6155e-02, -1.2805e-02, 1.0830e-02)),
    "panda_link4": (3.587895, (-5.317e-02, 1.04419e-01, 2.7454e-02), (2.5853e-02, 7.7960e-03, -1.3320e-03, 1.9552e-02, 8.6410e-03, 2.8323e-02)),
    "panda_link5": (1.225946, (-1.1953e-02, 4.1065e-02, -3.8437e-02), (3.5549e-02, -2.1170e-03, -4.0370e-03, 2.9474e-02, 2.2900e-04, 8.6270e-03)),
    "panda_link6": (1.666555, (6.0149e-02, -1.4117e-02, -1.0517e-02), (1.9640e-03, 1.0900e-04, -1.1580e-03, 4.3540e-03, 3.4100e-04, 5.4330e-03)),
    "panda_link7": (7.35522e-01, (1.0517e-02, -4.252e-03, 6.1597e-02), (1.2516e-02, -4.2800e-04, -1.1960e-03, 1.0027e-02, -7.4100e-04, 4.8150e-03)),
}
# The other links: mass (kg), CoM (m), inertia. Inertia: ("diag", ixx, iyy, izz) + CAD noise,
# ("box", sx, sy, sz) + CAD noise, ("rod_z", length) (izz written -1e-22), ("zero",), or None for
# an explicit massless <inertial> (mass 0), as franka_description writes panda_link8 and panda_hand_tcp.
OTHER = {
    "panda_link0": (0.629769, (-0.041018, -0.00014, 0.049974), ("box", 0.22, 0.16, 0.12)),
    "panda_link8": (0.0, (0.0, 0.0, 0.0), None),
    "panda_hand": (0.73, (-0.01, 0.0, 0.03), ("diag", 0.001, 0.0025, 0.0017)),
    "panda_hand_tcp": (0.0, (0.0, 0.0, 0.0), None),
    "panda_camera_mount": (0.01, (0.0, 0.0, 0.0), ("zero",)),
    "panda_camera": (0.02, (0.0, 0.0, 0.0), ("box", 0.025, 0.09, 0.025)),
    "panda_leftfinger": (0.015, (0.0, 0.012, 0.025), ("box", 0.02, 0.018, 0.05)),
    "panda_rightfinger": (0.015, (0.0, -0.012, 0.025), ("rod_z", 0.05)),
}
# panda_link0 is not given one: on the root of a fixed base the loader does not check (nor project) the
# inertia, and RobotModel then hands it to Simbody, which aborts (reported; see README.md).
TRIANGLE_EPS = {"panda_camera": 0.002, "panda_leftfinger": 0.003}
# The gripper. Franka hand: flange -> hand rotated -45 deg about z; fingers at 0.0584 m; TCP at 0.1034 m.
FINGER = (0.0, 0.04, 0.2, 100.0)  # lower, upper (m), velocity (m/s), effort (N)
READY = {"panda_joint1": 0.0, "panda_joint2": -math.pi / 4, "panda_joint3": 0.0, "panda_joint4": -3 * math.pi / 4,
         "panda_joint5": 0.0, "panda_joint6": HALF_PI, "panda_joint7": math.pi / 4}
PUBLISHED_MASS = 18.0   # kg, the arm
PUBLISHED_REACH = 0.855  # m

# Visual shapes (link frame, E): ("box", center, size) or ("cyl", p0, p1, radius).
FINGER_SHAPES = [("box", (0.0, 0.018, 0.01), (0.022, 0.016, 0.02)), ("box", (0.0, 0.009, 0.035), (0.018, 0.014, 0.03))]
VISUAL = {
    "link0": [("cyl", (0.0, 0.0, 0.0), (0.0, 0.0, 0.14), 0.075), ("box", (-0.07, 0.0, 0.05), (0.14, 0.12, 0.1))],
    "link1": [("cyl", (0.0, 0.0, -0.193), (0.0, 0.0, 0.0), 0.06), ("cyl", (0.0, -0.06, 0.0), (0.0, 0.06, 0.0), 0.06)],
    "link2": [("cyl", (0.0, 0.0, 0.0), (0.0, -0.15, 0.0), 0.06), ("cyl", (0.0, 0.0, -0.06), (0.0, 0.0, 0.06), 0.06)],
    "link3": [("cyl", (0.0, 0.0, -0.166), (0.0, 0.0, 0.0), 0.06), ("cyl", (0.0, 0.0, 0.0), (0.0825, 0.0, 0.0), 0.055),
              ("cyl", (0.0825, 0.0, -0.055), (0.0825, 0.0, 0.055), 0.055)],
    "link4": [("cyl", (0.0, 0.0, 0.0), (-0.0825, 0.0, 0.0), 0.055), ("cyl", (-0.0825, 0.0, 0.0), (-0.0825, 0.12, 0.0), 0.055)],
    "link5": [("cyl", (0.0, 0.0, -0.264), (0.0, 0.0, 0.0), 0.05), ("cyl", (0.0, -0.05, 0.0), (0.0, 0.05, 0.0), 0.05)],
    "link6": [("cyl", (0.0, 0.0, -0.05), (0.0, 0.0, 0.05), 0.05), ("cyl", (0.0, 0.0, 0.0), (0.088, 0.0, 0.0), 0.045)],
    "link7": [("cyl", (0.0, 0.0, 0.0), (0.0, 0.0, 0.09), 0.045)],
    "hand": [("box", (0.0, 0.0, 0.03), (0.06, 0.2, 0.06))],
    "camera": [("box", (0.0, 0.0, 0.0), (0.025, 0.09, 0.025))],
    "finger": FINGER_SHAPES,
}


# ---------------------------------------------------------------------------------------------
# Small linear algebra (3-vectors as tuples, 3x3 matrices as row tuples)
# ---------------------------------------------------------------------------------------------
def vadd(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def vsub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def vscale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    return math.sqrt(dot(a, a))


def mmul(A, B):
    return tuple(tuple(sum(A[i][k] * B[k][j] for k in range(3)) for j in range(3)) for i in range(3))


def mvec(A, v):
    return tuple(sum(A[i][k] * v[k] for k in range(3)) for i in range(3))


IDENTITY = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def rot_axis(axis, q):
    x, y, z = axis
    c, s, t = math.cos(q), math.sin(q), 1.0 - math.cos(q)
    return ((t * x * x + c, t * x * y - s * z, t * x * z + s * y),
            (t * x * y + s * z, t * y * y + c, t * y * z - s * x),
            (t * x * z - s * y, t * y * z + s * x, t * z * z + c))


def rpy_matrix(rpy):
    r, p, y = rpy
    return mmul(rot_axis((0.0, 0.0, 1.0), y), mmul(rot_axis((0.0, 1.0, 0.0), p), rot_axis((1.0, 0.0, 0.0), r)))


def eig_sym3(A):
    """Ascending eigenvalues of a symmetric 3x3 matrix (closed form)."""
    p1 = A[0][1] ** 2 + A[0][2] ** 2 + A[1][2] ** 2
    if p1 == 0.0:
        return sorted([A[0][0], A[1][1], A[2][2]])
    q = (A[0][0] + A[1][1] + A[2][2]) / 3.0
    p2 = (A[0][0] - q) ** 2 + (A[1][1] - q) ** 2 + (A[2][2] - q) ** 2 + 2.0 * p1
    p = math.sqrt(p2 / 6.0)
    B = tuple(tuple((A[i][j] - (q if i == j else 0.0)) / p for j in range(3)) for i in range(3))
    det = (B[0][0] * (B[1][1] * B[2][2] - B[1][2] * B[2][1]) - B[0][1] * (B[1][0] * B[2][2] - B[1][2] * B[2][0])
           + B[0][2] * (B[1][0] * B[2][1] - B[1][1] * B[2][0]))
    r = max(-1.0, min(1.0, det / 2.0))
    phi = math.acos(r) / 3.0
    e1 = q + 2.0 * p * math.cos(phi)
    e3 = q + 2.0 * p * math.cos(phi + 2.0 * math.pi / 3.0)
    return sorted([e3, 3.0 * q - e1 - e3, e1])


def inertia_class(I):
    """The loader's classification (lexdyn/model/inertia.cpp): zero, valid, noise, impossible."""
    m = eig_sym3(I)
    largest = max(abs(m[0]), abs(m[2]))
    if largest < 1e-12:
        return "zero", m, 0.0
    rounding = 1e-12 * largest
    noise = 1e-2 * largest + 1e-9
    negative, excess = -m[0], m[2] - m[0] - m[1]
    if negative <= rounding and excess <= rounding:
        return "valid", m, excess
    if negative > noise or excess > noise:
        return "impossible", m, excess
    return "noise", m, excess


# ---------------------------------------------------------------------------------------------
# Formatting (deterministic)
# ---------------------------------------------------------------------------------------------
def num(v):
    """A length or angle: at most 10 significant digits, no -0."""
    if abs(v) < 1e-15:
        return "0"
    s = "%.10g" % v
    return s


def cad(v):
    """An inertia entry as a CAD exporter writes it: small values in E notation."""
    if v == 0.0:
        return "0"
    if abs(v) < 1e-4:
        return "%.6E" % v
    return "%.10g" % v


def vec(v):
    return " ".join(num(x) for x in v)


def angles(v):
    """Angles (rpy) in full precision, as xacro writes pi/2: 1.5707963267948966."""
    return " ".join("0" if x == 0.0 else repr(x) for x in v)


# ---------------------------------------------------------------------------------------------
# Meshes: binary STL
# ---------------------------------------------------------------------------------------------
def box_triangles(center, size):
    cx, cy, cz = center
    hx, hy, hz = size[0] / 2, size[1] / 2, size[2] / 2
    v = [(cx + sx * hx, cy + sy * hy, cz + sz * hz) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    # vertex index = 4 * (sx > 0) + 2 * (sy > 0) + (sz > 0)
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = []
    for a, b, c, d in faces:
        tris.append((v[a], v[b], v[c]))
        tris.append((v[a], v[c], v[d]))
    return tris


def cylinder_triangles(p0, p1, r, n=16):
    axis = vsub(p1, p0)
    L = norm(axis)
    a = vscale(axis, 1.0 / L)
    helper = (1.0, 0.0, 0.0) if abs(a[0]) < 0.9 else (0.0, 1.0, 0.0)
    u = cross(a, helper)
    u = vscale(u, 1.0 / norm(u))
    w = cross(a, u)
    ring0, ring1 = [], []
    for k in range(n):
        t = 2.0 * math.pi * k / n
        off = vadd(vscale(u, r * math.cos(t)), vscale(w, r * math.sin(t)))
        ring0.append(vadd(p0, off))
        ring1.append(vadd(p1, off))
    tris = []
    for k in range(n):
        k1 = (k + 1) % n
        tris.append((ring0[k], ring0[k1], ring1[k1]))
        tris.append((ring0[k], ring1[k1], ring1[k]))
        tris.append((p0, ring0[k1], ring0[k]))
        tris.append((p1, ring1[k], ring1[k1]))
    return tris


def stl_bytes(title, tris):
    header = title.encode("ascii")[:80].ljust(80, b" ")
    out = [header, struct.pack("<I", len(tris))]
    for a, b, c in tris:
        nrm = cross(vsub(b, a), vsub(c, a))
        ln = norm(nrm)
        nrm = vscale(nrm, 1.0 / ln) if ln > 0 else (0.0, 0.0, 0.0)
        out.append(struct.pack("<12fH", *(nrm + a + b + c), 0))
    return b"".join(out)


def shape_triangles(shapes):
    tris = []
    for s in shapes:
        tris += box_triangles(s[1], s[2]) if s[0] == "box" else cylinder_triangles(s[1], s[2], s[3])
    return tris




# ---------------------------------------------------------------------------------------------
# The model
# ---------------------------------------------------------------------------------------------
def dh_origin(a, d, alpha):
    """URDF origin (xyz, rpy) of a modified-DH joint: Rx(alpha) Tx(a) Tz(d)."""
    return (a, -math.sin(alpha) * d, math.cos(alpha) * d), (alpha, 0.0, 0.0)


def joint(name, jtype, parent, child, xyz, rpy=(0.0, 0.0, 0.0), axis=None, limit=None, mimic=None, extras=()):
    return {"name": name, "type": jtype, "parent": parent, "child": child, "xyz": xyz, "rpy": rpy, "axis": axis,
            "limit": limit, "mimic": mimic, "extras": list(extras)}


def build():
    joints = [joint("world_joint", "fixed", "world", "panda_link0", (0.0, 0.0, 0.0), extras=["zero_axis"])]
    for i, (name, a, d, alpha) in enumerate(DH):
        xyz, rpy = dh_origin(a, d, alpha)
        parent, child = "panda_link%d" % i, "panda_link%d" % (i + 1)
        if name == "panda_joint8":
            joints.append(joint(name, "fixed", parent, child, xyz, rpy, extras=["zero_axis"]))
        else:
            joints.append(joint(name, "revolute", parent, child, xyz, rpy, (0.0, 0.0, 1.0), LIMITS[name],
                                extras=["safety", "franka_dynamics"]))
    lo, up, vel, eff = FINGER
    joints += [
        joint("panda_hand_joint", "fixed", "panda_link8", "panda_hand", (0.0, 0.0, 0.0), (0.0, 0.0, -math.pi / 4), extras=["zero_axis"]),
        joint("panda_hand_tcp_joint", "fixed", "panda_hand", "panda_hand_tcp", (0.0, 0.0, 0.1034), extras=["zero_limit"]),
        joint("panda_camera_mount_joint", "fixed", "panda_hand", "panda_camera_mount", (0.045, 0.0, 0.03), extras=["zero_axis"]),
        joint("panda_camera_joint", "fixed", "panda_camera_mount", "panda_camera", (0.0125, 0.0, 0.0), extras=["zero_axis"]),
        joint("panda_finger_joint1", "prismatic", "panda_hand", "panda_leftfinger", (0.0, 0.0, 0.0584), axis=(0.0, 1.0, 0.0),
              limit=(lo, up, vel, eff), extras=["finger_dynamics"]),
        joint("panda_finger_joint2", "prismatic", "panda_hand", "panda_rightfinger", (0.0, 0.0, 0.0584), axis=(0.0, -1.0, 0.0),
              limit=(lo, up, vel, eff), mimic=("panda_finger_joint1", 1.0, 0.0), extras=["finger_dynamics"]),
        joint("panda_leftfinger_tip_joint", "fixed", "panda_leftfinger", "panda_leftfinger_tip", (0.0, 0.0076, 0.045),
              mimic=("panda_finger_joint1", 1.0, 0.0), extras=["zero_axis"]),
        joint("panda_rightfinger_tip_joint", "fixed", "panda_rightfinger", "panda_rightfinger_tip", (0.0, -0.0076, 0.045)),
    ]
    links = {"world": None, "panda_leftfinger_tip": None, "panda_rightfinger_tip": None}
    for name, (m, com, i6) in GAZ.items():
        links[name] = {"mass": m, "com": com, "inertia": ("full",) + i6}
    for name, (m, com, ine) in OTHER.items():
        links[name] = {"mass": m, "com": com, "inertia": ine}
    for name, link in links.items():
        if link is None:
            continue
        short = name[len("panda_"):]
        if short.startswith("link") and short != "link8":
            link["visual"], link["collision"] = (short, (0.0, 0.0, 0.0)), [("mesh", short)]
        elif short == "hand":
            link["visual"], link["collision"] = ("hand", (0.0, 0.0, 0.0)), [("mesh", "hand")]
        elif short == "leftfinger":
            link["visual"], link["collision"] = ("finger", (0.0, 0.0, 0.0)), [("box",) + s[1:] for s in FINGER_SHAPES]
        elif short == "camera":
            link["visual"], link["collision"] = ("camera", (0.0, 0.0, 0.0)), []
        elif short == "rightfinger":
            link["visual"] = ("finger", (0.0, 0.0, math.pi))  # the left finger's mesh turned half a turn, as franka_description does
            link["collision"] = [("box", (s[1][0], -s[1][1], s[1][2]), s[2]) for s in FINGER_SHAPES]
        else:
            link["visual"], link["collision"] = None, []
    return joints, links


def noise_offdiag(name):
    """Three deterministic off-diagonal terms of magnitude 1e-10..1e-8 (CAD rounding noise)."""
    h = hashlib.sha256(name.encode()).digest()
    out = []
    for k in range(3):
        u = h[2 * k] / 255.0
        sign = -1.0 if h[2 * k + 1] & 1 else 1.0
        out.append(sign * float("%.4g" % (10.0 ** (-8.0 - 2.0 * u))))
    return out


def inertia_of(name, link):
    """(ixx, ixy, ixz, iyy, iyz, izz) about the CoM as written, or None for a massless <inertial>."""
    m, ine = link["mass"], link["inertia"]
    if ine is None:
        return None
    if ine[0] == "full":
        return ine[1:]
    if ine[0] == "zero":
        return (0.0,) * 6
    if ine[0] == "rod_z":
        t = float("%.8g" % (m * ine[1] ** 2 / 12))
        return (t, 0.0, 0.0, t, 0.0, -1e-22)
    if ine[0] == "diag":
        d = list(ine[1:])
    else:
        a, b, c = ine[1:]
        d = [float("%.8g" % v) for v in (m / 12 * (b * b + c * c), m / 12 * (a * a + c * c), m / 12 * (a * a + b * b))]
    if name in TRIANGLE_EPS:
        k = d.index(max(d))
        others = [d[i] for i in range(3) if i != k]
        d[k] = float("%.8g" % ((others[0] + others[1]) * (1.0 + TRIANGLE_EPS[name])))
    xy, xz, yz = noise_offdiag(name)
    return (d[0], xy, xz, d[1], yz, d[2])


def matrix6(i6):
    ixx, ixy, ixz, iyy, iyz, izz = i6
    return ((ixx, ixy, ixz), (ixy, iyy, iyz), (ixz, iyz, izz))


# ---------------------------------------------------------------------------------------------
# Writers
# ---------------------------------------------------------------------------------------------
def mesh_uri(mesh):
    return "package://%s/meshes/%s.stl" % (PKG, mesh)


def write_link(name, link):
    if link is None:
        return '  <link name="%s"/>\n' % name
    out = ['  <link name="%s">\n' % name]
    if link["visual"]:
        mesh, rpy = link["visual"]
        out += ['    <visual>\n',
                '      <origin xyz="0 0 0" rpy="%s"/>\n' % angles(rpy),
                '      <geometry>\n',
                '        <mesh filename="%s"/>\n' % mesh_uri(mesh),
                '      </geometry>\n',
                '    </visual>\n']
    for c in link["collision"]:
        origin = (0.0, 0.0, 0.0) if c[0] == "mesh" else c[1]
        geom = '<mesh filename="%s"/>' % mesh_uri(c[1]) if c[0] == "mesh" else '<box size="%s"/>' % vec(c[2])
        out += ['    <collision>\n',
                '      <origin xyz="%s" rpy="0 0 0"/>\n' % vec(origin),
                '      <geometry>\n',
                '        %s\n' % geom,
                '      </geometry>\n',
                '    </collision>\n']
    i6 = inertia_of(name, link)
    out += ['    <inertial>\n',
            '      <origin xyz="%s" rpy="0 0 0"/>\n' % vec(link["com"]),
            '      <mass value="%s"/>\n' % num(link["mass"]),
            '      <inertia ixx="%s" ixy="%s" ixz="%s" iyy="%s" iyz="%s" izz="%s"/>\n' % tuple(cad(v) for v in (i6 or (0.0,) * 6)),
            '    </inertial>\n',
            '  </link>\n']
    return "".join(out)


def write_joint(j):
    out = ['  <joint name="%s" type="%s">\n' % (j["name"], j["type"]),
           '    <origin xyz="%s" rpy="%s"/>\n' % (vec(j["xyz"]), angles(j["rpy"])),
           '    <parent link="%s"/>\n' % j["parent"],
           '    <child link="%s"/>\n' % j["child"]]
    if "zero_axis" in j["extras"]:
        out.append('    <axis xyz="0 0 0"/>\n')
    if "zero_limit" in j["extras"]:
        out.append('    <limit lower="0" upper="0" effort="0" velocity="0"/>\n')
    if j["axis"]:
        out.append('    <axis xyz="%s"/>\n' % vec(j["axis"]))
    if j["limit"]:
        lo, up, vel, eff = j["limit"]
        out.append('    <limit effort="%s" lower="%s" upper="%s" velocity="%s"/>\n' % (num(eff), num(lo), num(up), num(vel)))
    if j["mimic"]:
        out.append('    <mimic joint="%s"/>\n' % j["mimic"][0])  # multiplier 1 and offset 0 left to their defaults
    if "safety" in j["extras"]:
        lo, up = j["limit"][:2]
        out.append('    <safety_controller k_position="100.0" k_velocity="40.0" soft_lower_limit="%s" soft_upper_limit="%s"/>\n' % (num(lo), num(up)))
    if "franka_dynamics" in j["extras"]:
        out.append('    <dynamics D="1" K="7000" damping="0.003" friction="0.0" mu_coulomb="0" mu_viscous="16"/>\n')
    if "finger_dynamics" in j["extras"]:
        out.append('    <dynamics damping="0.3"/>\n')
    out.append('  </joint>\n')
    return "".join(out)


def write_urdf(joints, links):
    parts = [
        '<?xml version="1.0" ?>\n',
        "<!-- =================================================================================== -->\n"
        "<!-- |  Generated by models/panda_like/generate_urdf.py; do not edit by hand.             | -->\n"
        "<!-- |  A Franka-Emika-Panda-like arm from published figures and estimates (README.md),  | -->\n"
        "<!-- |  in the conventions of real description packages (world link, fixed joints with   | -->\n"
        "<!-- |  axis/limit/mimic, a mimic finger, package:// meshes, transmissions, gazebo).     | -->\n"
        "<!-- =================================================================================== -->\n",
        '<robot name="%s" xmlns:xacro="http://www.ros.org/wiki/xacro">\n' % ROBOT,
        write_link("world", None),
    ]
    for j in joints:
        parts.append(write_link(j["child"], links[j["child"]]))
        parts.append(write_joint(j))
    for j in sorted((j for j in joints if j["type"] != "fixed" and not j["mimic"]), key=lambda j: j["name"]):
        parts += ['  <transmission name="%s_transmission">\n' % j["name"],
                  '    <type>transmission_interface/SimpleTransmission</type>\n',
                  '    <joint name="%s">\n' % j["name"],
                  '      <hardwareInterface>hardware_interface/EffortJointInterface</hardwareInterface>\n',
                  '    </joint>\n',
                  '    <actuator name="%s_motor">\n' % j["name"],
                  '      <mechanicalReduction>1</mechanicalReduction>\n',
                  '    </actuator>\n',
                  '  </transmission>\n']
    parts += ['  <gazebo>\n',
              '    <plugin name="gazebo_ros_control" filename="libgazebo_ros_control.so">\n',
              '      <robotNamespace>/%s</robotNamespace>\n' % ROBOT,
              '    </plugin>\n',
              '  </gazebo>\n']
    for name in sorted(n for n in links if links[n] and links[n]["visual"]):
        parts += ['  <gazebo reference="%s">\n' % name,
                  '    <selfCollide>false</selfCollide>\n']
        if "finger" in name:
            parts += ['    <mu1>1.0</mu1>\n', '    <mu2>1.0</mu2>\n']
        parts.append('  </gazebo>\n')
    parts.append('</robot>\n')
    return "".join(parts)


def write_srdf(joints):
    arm = ["panda_joint%d" % i for i in range(1, 8)]
    out = ['<?xml version="1.0" encoding="UTF-8"?>\n',
           "<!-- Generated by models/panda_like/generate_urdf.py; do not edit by hand. -->\n",
           '<robot name="%s">\n' % ROBOT,
           '  <group name="panda_arm">\n',
           '    <chain base_link="panda_link0" tip_link="panda_link8"/>\n',
           '  </group>\n',
           '  <group name="hand">\n',
           '    <link name="panda_hand"/>\n',
           '    <link name="panda_leftfinger"/>\n',
           '    <link name="panda_rightfinger"/>\n',
           '    <joint name="panda_finger_joint1"/>\n',
           '    <passive_joint name="panda_finger_joint2"/>\n',
           '  </group>\n',
           '  <group name="panda_arm_hand">\n',
           '    <group name="panda_arm"/>\n',
           '    <group name="hand"/>\n',
           '  </group>\n',
           '  <group_state name="ready" group="panda_arm">\n']
    out += ['    <joint name="%s" value="%s"/>\n' % (n, num(READY[n])) for n in arm]
    out += ['  </group_state>\n',
            '  <group_state name="open" group="hand">\n',
            '    <joint name="panda_finger_joint1" value="0.035"/>\n',
            '  </group_state>\n',
            '  <group_state name="close" group="hand">\n',
            '    <joint name="panda_finger_joint1" value="0"/>\n',
            '  </group_state>\n',
            '  <end_effector name="hand" parent_link="panda_link8" group="hand" parent_group="panda_arm"/>\n',
            '  <passive_joint name="panda_finger_joint2"/>\n']
    pairs = sorted(tuple(sorted((j["parent"], j["child"]))) for j in joints if j["type"] != "fixed")
    pairs += [("panda_hand", "panda_link7"), ("panda_leftfinger", "panda_rightfinger"), ("panda_link0", "panda_link2")]
    out += ['  <disable_collisions link1="%s" link2="%s" reason="%s"/>\n'
            % (a, b, "Default" if (a, b) in (("panda_leftfinger", "panda_rightfinger"),) else
               "Never" if (a, b) == ("panda_link0", "panda_link2") else "Adjacent") for a, b in sorted(set(pairs))]
    out.append('</robot>\n')
    return "".join(out)


def write_package_xml():
    return ('<?xml version="1.0"?>\n'
            '<!-- Generated by models/panda_like/generate_urdf.py; do not edit by hand. -->\n'
            '<package format="2">\n'
            '  <name>%s</name>\n'
            '  <version>0.1.0</version>\n'
            '  <description>A Franka-Emika-Panda-like arm with a parallel gripper (lexdyn test model, written from published figures; not Franka\'s description).</description>\n'
            '  <maintainer email="lexdyn@localhost">lexdyn</maintainer>\n'
            '  <license>the license of the lexdyn repository</license>\n'
            '  <buildtool_depend>catkin</buildtool_depend>\n'
            '  <exec_depend>urdf</exec_depend>\n'
            '  <exec_depend>xacro</exec_depend>\n'
            '  <export>\n'
            '    <architecture_independent/>\n'
            '  </export>\n'
            '</package>\n') % PKG


# ---------------------------------------------------------------------------------------------
# Kinematics and checks
# ---------------------------------------------------------------------------------------------
def forward(joints, q):
    X = {"world": (IDENTITY, (0.0, 0.0, 0.0))}
    for j in joints:
        R, p = X[j["parent"]]
        Rj = mmul(R, rpy_matrix(j["rpy"]))
        pj = vadd(p, mvec(R, j["xyz"]))
        if j["type"] != "fixed":
            v = q.get(j["mimic"][0], 0.0) * j["mimic"][1] + j["mimic"][2] if j["mimic"] else q.get(j["name"], 0.0)
            if j["type"] == "prismatic":
                pj = vadd(pj, mvec(Rj, vscale(j["axis"], v)))
            else:
                Rj = mmul(Rj, rot_axis(j["axis"], v))
        X[j["child"]] = (Rj, pj)
    return X


def checks(joints, links, meshes):
    moving = [j for j in joints if j["type"] != "fixed"]
    mimics = [j for j in moving if j["mimic"]]
    fixed = [j for j in joints if j["type"] == "fixed"]
    assert len(moving) == 9 and len(mimics) == 1 and len(fixed) == 8
    print("joints: %d moving (7 arm + 2 fingers, %d mimic), %d fixed, %d links" % (len(moving), len(mimics), len(fixed), len(links)))

    mass = sum(l["mass"] for l in links.values() if l)
    arm = sum(links["panda_link%d" % i]["mass"] for i in range(8))
    assert abs(mass - PUBLISHED_MASS) < 1.0, mass
    print("total mass: %.3f kg (arm links 0-7 %.3f, hand with fingers and camera %.3f); published ~%.0f kg"
          % (mass, arm, mass - arm, PUBLISHED_MASS))

    X0 = forward(joints, {})
    pos = lambda X, n: X[n][1]
    reach = (norm(vsub(pos(X0, "panda_link4"), pos(X0, "panda_link2"))) + norm(vsub(pos(X0, "panda_link6"), pos(X0, "panda_link4")))
             + norm(vsub(pos(X0, "panda_link8"), pos(X0, "panda_link6"))))
    assert abs(reach - PUBLISHED_REACH) < 0.01, reach
    assert abs(pos(X0, "panda_link2")[2] - 0.333) < 1e-12 and abs(pos(X0, "panda_link6")[2] - 1.033) < 1e-12
    print("zero pose: shoulder %.3f m, wrist %.3f m, flange (%.4f, %.4f, %.4f) m; reach shoulder-elbow-wrist-flange %.4f m (published %.3f m)"
          % ((pos(X0, "panda_link2")[2], pos(X0, "panda_link6")[2]) + tuple(round(v, 6) + 0.0 for v in pos(X0, "panda_link8")) + (reach, PUBLISHED_REACH)))

    for n, v in READY.items():
        lo, up = LIMITS[n][:2]
        assert lo < v < up, n
    assert FINGER[0] <= 0.035 <= FINGER[1]
    X = forward(joints, READY)
    R, p = X["panda_hand_tcp"]
    down = ((1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, -1.0))
    assert max(abs(R[i][k] - down[i][k]) for i in range(3) for k in range(3)) < 1e-9, R
    print("ready: inside the limits; TCP at (%.4f, %.4f, %.4f) m pointing down, x forward" % tuple(round(v, 4) + 0.0 for v in p))

    classes = {}
    for name in sorted(n for n in links if links[n]):
        i6 = inertia_of(name, links[name])
        if i6 is None:
            classes.setdefault("massless", []).append(name)
            continue
        cls, m, excess = inertia_class(matrix6(i6))
        classes.setdefault(cls, []).append(name)
        if name in TRIANGLE_EPS:
            assert cls == "noise" and 0.001 <= excess / m[2] <= 0.005, (name, cls, excess / m[2])
        elif name == "panda_camera_mount":
            assert cls == "zero"
        elif name == "panda_rightfinger":
            assert cls == "valid" and m[0] < 0.0
        else:
            assert cls == "valid", (name, cls, m)
    print("inertias: valid %s; triangle inequality violated as rounding noise: %s; zero (point mass): %s; "
          "massless <inertial>: %s; a -1e-22 moment: panda_rightfinger"
          % (", ".join(classes["valid"]), ", ".join("%s (%.1f %%)" % (n, 100 * e) for n, e in sorted(TRIANGLE_EPS.items())),
             ", ".join(classes["zero"]), ", ".join(classes["massless"])))
    big = max(len(b) for b in meshes.values())
    assert big < 12288
    print("meshes: %d binary STL files, %d to %d bytes" % (len(meshes), min(len(b) for b in meshes.values()), big))


def write_file(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb" if isinstance(data, bytes) else "w") as f:
        f.write(data)


def main():
    joints, links = build()
    meshes = {name + ".stl": stl_bytes("%s/meshes/%s.stl (generated by generate_urdf.py)" % (PKG, name), shape_triangles(shapes))
              for name, shapes in sorted(VISUAL.items())}
    checks(joints, links, meshes)
    write_file(os.path.join(HERE, "package.xml"), write_package_xml())
    write_file(os.path.join(HERE, "urdf", ROBOT + ".urdf"), write_urdf(joints, links))
    write_file(os.path.join(HERE, "srdf", ROBOT + ".srdf"), write_srdf(joints))
    mesh_dir = os.path.join(HERE, "meshes")
    os.makedirs(mesh_dir, exist_ok=True)
    for old in sorted(os.listdir(mesh_dir)):
        if old.endswith(".stl") and old not in meshes:
            os.remove(os.path.join(mesh_dir, old))
    for name in sorted(meshes):
        write_file(os.path.join(mesh_dir, name), meshes[name])
    print("wrote package.xml, urdf/%s.urdf, srdf/%s.srdf, %d meshes under %s" % (ROBOT, ROBOT, len(meshes), os.path.relpath(HERE)))


if __name__ == "__main__":
    sys.exit(main())
