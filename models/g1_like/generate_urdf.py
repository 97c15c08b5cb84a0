#!/usr/bin/env python3
"""Writes the g1_like_description package: a Unitree-G1-like humanoid, in the conventions of
real ROS description packages (see README.md for every figure and its source).

    /usr/bin/python3 models/g1_like/generate_urdf.py

writes, next to this script (all deterministic: byte-identical on every run):
    package.xml                 the ROS package manifest (name g1_like_description)
    urdf/g1_like.urdf           links, joints, limits, CAD-style inertias, meshes, extras
    srdf/g1_like.srdf           groups, the "standing" group_state, end effectors
    meshes/<link>.stl           small binary STL meshes (boxes and 16-facet cylinders, metres)
and prints its checks (total mass, height, leg length, joint counts, the standing posture
inside the limits with the feet flat, the inertia classes). Every check is an assertion.

The tables below are the model's source of truth. The left side is written; the right side
negates y and maps roll/yaw (x/z axis) limits [l, u] to [-u, -l]. Pure Python, no numpy.
"""
import hashlib
import math
import os
import struct
import sys

ROBOT = "g1_like"
PKG = "g1_like_description"
HERE = os.path.dirname(os.path.abspath(__file__))
AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}

# ---------------------------------------------------------------------------------------------
# Joint table. Left side (and the unsided joints).
# name, type, parent, child, origin xyz, origin rpy, axis, lower, upper, effort (Nm), velocity (rad/s)
# ---------------------------------------------------------------------------------------------
LEG = [
    ("hip_pitch_joint", "revolute", "pelvis", "hip_pitch_link", (0.0, 0.064452, -0.1027), "y", -2.5307, 2.8798, 88.0, 32.0),
    ("hip_roll_joint", "revolute", "hip_pitch_link", "hip_roll_link", (0.0, 0.052, -0.030465), "x", -0.5236, 2.9671, 139.0, 20.0),
    ("hip_yaw_joint", "revolute", "hip_roll_link", "hip_yaw_link", (0.0, 0.0, -0.118), "z", -2.7576, 2.7576, 88.0, 32.0),
    ("knee_joint", "revolute", "hip_yaw_link", "knee_link", (0.0, 0.0, -0.188), "y", -0.087267, 2.8798, 139.0, 20.0),
    ("ankle_pitch_joint", "revolute", "knee_link", "ankle_pitch_link", (0.0, 0.0, -0.3), "y", -0.87267, 0.5236, 35.0, 30.0),
    ("ankle_roll_joint", "revolute", "ankle_pitch_link", "ankle_roll_link", (0.0, 0.0, -0.017558), "x", -0.2618, 0.2618, 35.0, 30.0),
    ("sole_joint", "fixed", "ankle_roll_link", "sole_link", (0.0, 0.0, -0.0354), None, 0, 0, 0, 0),
]
ARM = [
    ("shoulder_pitch_joint", "revolute", "torso_link", "shoulder_pitch_link", (0.0039563, 0.1002, 0.29178), "y", -3.0892, 2.6704, 25.0, 37.0),
    ("shoulder_roll_joint", "revolute", "shoulder_pitch_link", "shoulder_roll_link", (0.0, 0.038, -0.013831), "x", -1.5882, 2.2515, 25.0, 37.0),
    ("shoulder_yaw_joint", "revolute", "shoulder_roll_link", "shoulder_yaw_link", (0.0, 0.00624, -0.1032), "z", -2.618, 2.618, 25.0, 37.0),
    ("elbow_joint", "revolute", "shoulder_yaw_link", "elbow_link", (0.015783, 0.0, -0.080518), "y", -1.0472, 2.0944, 25.0, 37.0),
    ("wrist_roll_joint", "revolute", "elbow_link", "wrist_roll_link", (0.1, 0.00188791, -0.01), "x", -1.972222054, 1.972222054, 25.0, 37.0),
    ("wrist_pitch_joint", "revolute", "wrist_roll_link", "wrist_pitch_link", (0.038, 0.0, 0.0), "y", -1.614429558, 1.614429558, 5.0, 22.0),
    ("wrist_yaw_joint", "revolute", "wrist_pitch_link", "wrist_yaw_link", (0.046, 0.0, 0.0), "z", -1.614429558, 1.614429558, 5.0, 22.0),
    ("hand_palm_joint", "fixed", "wrist_yaw_link", "hand_palm_link", (0.0415, 0.003, 0.0), None, 0, 0, 0, 0),
    # A 1-DoF three-finger hand: the thumb is the master, index and middle mimic it (x -1).
    ("hand_thumb_0_joint", "revolute", "hand_palm_link", "hand_thumb_0_link", (0.0255, -0.021, 0.0), "z", 0.0, 1.0472, 1.4, 12.0),
    ("hand_index_0_joint", "revolute", "hand_palm_link", "hand_index_0_link", (0.087, 0.0, 0.0285), "z", -1.5708, 0.0, 1.4, 12.0),
    ("hand_index_1_joint", "fixed", "hand_index_0_link", "hand_index_1_link", (0.045, 0.0, 0.0), None, 0, 0, 0, 0),
    ("hand_middle_0_joint", "revolute", "hand_palm_link", "hand_middle_0_link", (0.087, 0.0, -0.0285), "z", -1.5708, 0.0, 1.4, 12.0),
]
CENTER = [
    ("base_joint", "fixed", "base_link", "pelvis", (0.0, 0.0, 0.0), None, 0, 0, 0, 0),
    ("imu_in_pelvis_joint", "fixed", "pelvis", "imu_in_pelvis", (0.04525, 0.0, -0.08339), None, 0, 0, 0, 0),
    ("waist_yaw_joint", "revolute", "pelvis", "torso_link", (0.0, 0.0, 0.0), "z", -2.618, 2.618, 88.0, 32.0),
    ("head_joint", "fixed", "torso_link", "head_link", (0.0, 0.0, 0.4), None, 0, 0, 0, 0),
    ("imu_in_torso_joint", "fixed", "torso_link", "imu_in_torso", (-0.03959, -0.00224, 0.19192), None, 0, 0, 0, 0),
    ("d435_joint", "fixed", "torso_link", "d435_link", (0.0576235, 0.01753, 0.47387), None, 0, 0, 0, 0),
]
FIXED_RPY = {"d435_joint": (0.0, 0.8307767239493009, 0.0)}  # the head camera looks down (P)
# Mimic joints: joint -> (master, multiplier, offset), on both sides.
MIMIC = {
    "hand_index_0_joint": ("hand_thumb_0_joint", -1.0, 0.0),
    "hand_middle_0_joint": ("hand_thumb_0_joint", -1.0, 0.0),
}
# The one <mimic> on a fixed joint (the distal index phalanx; a variant with a coupled distal
# joint had it moving, and the export kept the mimic): left side only.
FIXED_MIMIC = {"left_hand_index_1_joint": ("left_hand_index_0_joint", 1.0, 0.0)}
# Fixed joints carrying <axis xyz="0 0 0"/> (CAD exporters write it).
ZERO_AXIS = ["base_joint", "head_joint", "left_sole_joint", "right_sole_joint", "left_hand_palm_joint",
             "right_hand_palm_joint", "right_hand_index_1_joint", "imu_in_pelvis_joint"]
ZERO_LIMIT = ["imu_in_pelvis_joint"]  # <limit lower="0" upper="0" effort="0" velocity="0"/>
# <dynamics> and <safety_controller> on a few joints (E); both sides.
DYNAMICS = {"hip_pitch_joint": (0.05, 0.2), "knee_joint": (0.05, 0.3), "ankle_pitch_joint": (0.02, 0.1)}
SAFETY = {"knee_joint": (-0.05, 2.85, 100.0, 20.0)}  # soft lower, soft upper, k_position, k_velocity

# ---------------------------------------------------------------------------------------------
# Link table (left side). mass (kg), CoM (m), inertia shape about the CoM, visual shapes.
# Inertia shapes: ("box", sx, sy, sz) or ("cyl", axis, radius, length) or ("zero",).
# Visual shapes (link frame): ("box", center, size) or ("cyl", p0, p1, radius).
# ---------------------------------------------------------------------------------------------
LINKS = {
    "pelvis": (3.8, (0.0, 0.0, -0.076), ("box", 0.0975, 0.129, 0.15),
               [("box", (0.0, 0.0, -0.0725), (0.0975, 0.129, 0.15))]),
    "imu_in_pelvis": (0.02, (0.0, 0.0, 0.0), ("zero",), []),
    "hip_pitch_link": (1.35, (0.003, 0.048, -0.026), ("cyl", "y", 0.05, 0.06),
                       [("cyl", (0.0, 0.0, 0.0), (0.0, 0.06, 0.0), 0.045), ("cyl", (0.0, 0.052, 0.0), (0.0, 0.052, -0.03), 0.03)]),
    "hip_roll_link": (1.52, (0.01, 0.0, -0.07), ("cyl", "z", 0.05, 0.12),
                      [("cyl", (-0.04, 0.0, 0.0), (0.04, 0.0, 0.0), 0.045), ("cyl", (0.0, 0.0, 0.0), (0.0, 0.0, -0.118), 0.04)]),
    "hip_yaw_link": (1.70, (-0.01, 0.0, -0.1), ("cyl", "z", 0.055, 0.19),
                     [("cyl", (0.0, 0.0, 0.0), (0.0, 0.0, -0.188), 0.05), ("cyl", (0.0, -0.04, -0.188), (0.0, 0.04, -0.188), 0.045)]),
    "knee_link": (1.93, (0.005, 0.0, -0.12), ("cyl", "z", 0.045, 0.3),
                  [("cyl", (0.0, 0.0, 0.0), (0.0, 0.0, -0.3), 0.04)]),
    "ankle_pitch_link": (0.074, (0.0, 0.0, 0.0), ("cyl", "y", 0.008, 0.05),
                         [("cyl", (0.0, -0.025, 0.0), (0.0, 0.025, 0.0), 0.01)]),
    "ankle_roll_link": (0.608, (0.027, 0.0, -0.016), ("box", 0.208, 0.076, 0.03),
                        [("box", (0.038, 0.0, -0.0254), (0.208, 0.076, 0.02)), ("box", (0.0, 0.0, -0.003), (0.06, 0.05, 0.045))]),
    "sole_link": None,
    "torso_link": (8.2, (0.0, 0.0, 0.19), ("box", 0.15, 0.215, 0.32),
                   [("box", (0.0085, 0.0, 0.195), (0.15, 0.215, 0.32))]),
    "head_link": (1.0, (0.005, 0.0, 0.05), ("box", 0.14, 0.156, 0.206),
                  [("box", (0.004, 0.0, 0.0277), (0.14, 0.156, 0.206))]),
    "imu_in_torso": None,
    "d435_link": None,
    "shoulder_pitch_link": (0.718, (0.0, 0.036, -0.012), ("cyl", "y", 0.04, 0.06),
                            [("cyl", (0.0, 0.0, 0.0), (0.0, 0.05, 0.0), 0.04)]),
    "shoulder_roll_link": (0.643, (0.0, 0.007, -0.063), ("cyl", "z", 0.035, 0.1),
                           [("cyl", (-0.035, 0.0, 0.0), (0.035, 0.0, 0.0), 0.035), ("cyl", (0.0, 0.006, 0.0), (0.0, 0.006, -0.1032), 0.035)]),
    "shoulder_yaw_link": (0.734, (0.01, 0.0, -0.06), ("cyl", "z", 0.035, 0.09),
                          [("cyl", (0.0, 0.0, 0.0), (0.0, 0.0, -0.08), 0.035), ("cyl", (0.0158, -0.03, -0.0805), (0.0158, 0.03, -0.0805), 0.035)]),
    "elbow_link": (0.6, (0.065, 0.0, -0.01), ("cyl", "x", 0.03, 0.11),
                   [("cyl", (0.0, 0.0, 0.0), (0.1, 0.0, -0.01), 0.03)]),
    "wrist_roll_link": (0.085, (0.017, 0.0, 0.0), ("cyl", "x", 0.025, 0.035),
                        [("cyl", (0.0, 0.0, 0.0), (0.038, 0.0, 0.0), 0.025)]),
    "wrist_pitch_link": (0.484, (0.023, 0.0, 0.0), ("cyl", "y", 0.028, 0.05),
                         [("cyl", (0.0, -0.025, 0.0), (0.0, 0.025, 0.0), 0.025), ("cyl", (0.0, 0.0, 0.0), (0.046, 0.0, 0.0), 0.022)]),
    "wrist_yaw_link": (0.085, (0.022, 0.0, 0.0), ("cyl", "x", 0.02, 0.04),
                       [("cyl", (0.0, 0.0, -0.02), (0.0, 0.0, 0.02), 0.02), ("cyl", (0.0, 0.0, 0.0), (0.0415, 0.0, 0.0), 0.02)]),
    "hand_palm_link": (0.35, (0.0435, 0.0, 0.0), ("box", 0.087, 0.042, 0.088),
                       [("box", (0.0435, 0.0, 0.0), (0.087, 0.042, 0.088))]),
    "hand_thumb_0_link": (0.06, (0.0, -0.0225, 0.0), ("box", 0.02, 0.045, 0.02),
                          [("box", (0.0, -0.0225, 0.0), (0.02, 0.045, 0.02))]),
    "hand_index_0_link": (0.04, (0.0225, 0.0, 0.0), ("box", 0.045, 0.02, 0.02),
                          [("box", (0.0225, 0.0, 0.0), (0.045, 0.02, 0.02))]),
    "hand_index_1_link": (0.02, (0.015, 0.0, 0.0), ("box", 0.03, 0.018, 0.018),
                          [("box", (0.015, 0.0, 0.0), (0.03, 0.018, 0.018))]),
    "hand_middle_0_link": (0.05, (0.03, 0.0, 0.0), ("box", 0.06, 0.02, 0.02),
                           [("box", (0.03, 0.0, 0.0), (0.06, 0.02, 0.02))]),
}
# CAD noise, per final link name: the largest principal moment made (1 + eps) times the sum of
# the two others (a triangle-inequality violation of eps relative), and the near-zero moment.
TRIANGLE_EPS = {"left_ankle_roll_link": 0.002, "right_ankle_roll_link": 0.003, "left_hand_palm_link": 0.004}
MINUS_1E22 = {"left_ankle_pitch_link": "iyy"}  # a thin shaft along y: CAD writes -1e-22 for its axial moment
# Collision geometry: the soles (boxes whose lowest face is the sole), the hands (meshes), and
# a box for the torso and a sphere for the head. ("box", center, size) / ("mesh",) / ("sphere", center, r)
COLLISION = {
    "ankle_roll_link": [("box", (0.038, 0.0, -0.0254), (0.208, 0.076, 0.02))],
    "hand_palm_link": [("mesh",)],
    "hand_thumb_0_link": [("mesh",)],
    "hand_index_0_link": [("mesh",)],
    "hand_index_1_link": [("mesh",)],
    "hand_middle_0_link": [("mesh",)],
    "torso_link": [("box", (0.0085, 0.0, 0.195), (0.15, 0.215, 0.32))],
    "head_link": [("sphere", (0.004, 0.0, 0.03), 0.08)],
}
MATERIAL = {"pelvis": "dark", "torso_link": "white", "head_link": "dark"}  # default: white for links, dark for hands

# The "standing" posture (knees bent 0.3 rad, hip and ankle pitch -0.15 each so that the feet
# stay flat, arms slightly away from the body). Left side; the right side mirrors roll and yaw.
STANDING = {
    "hip_pitch_joint": -0.15, "hip_roll_joint": 0.0, "hip_yaw_joint": 0.0, "knee_joint": 0.3,
    "ankle_pitch_joint": -0.15, "ankle_roll_joint": 0.0, "waist_yaw_joint": 0.0,
    "shoulder_pitch_joint": 0.0, "shoulder_roll_joint": 0.25, "shoulder_yaw_joint": 0.0, "elbow_joint": 0.9,
    "wrist_roll_joint": 0.0, "wrist_pitch_joint": 0.0, "wrist_yaw_joint": 0.0, "hand_thumb_0_joint": 0.1,
}

# Published figures the checks compare with (README.md, P).
PUBLISHED_HEIGHT = 1.32
PUBLISHED_MASS = 35.0
PUBLISHED_LEG = 0.60


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
# The model: both sides expanded
# ---------------------------------------------------------------------------------------------
def mirror_y(p):
    return (p[0], -p[1], p[2])


def mirror_shape(s):
    if s[0] == "box":
        return ("box", mirror_y(s[1]), s[2])
    if s[0] == "cyl":
        return ("cyl", mirror_y(s[1]), mirror_y(s[2]), s[3])
    if s[0] == "sphere":
        return ("sphere", mirror_y(s[1]), s[2])
    return s


def build():
    """Joints (tree order) and links, both sides."""
    joints, links = [], {}
    unsided = {"pelvis", "torso_link", "base_link"}

    def add_links(key, final, mirror):
        spec = LINKS.get(key)
        if spec is None:
            links[final] = None
            return
        mass, com, shape, visual = spec
        if mirror:
            com = mirror_y(com)
            visual = [mirror_shape(s) for s in visual]
        coll = [mirror_shape(s) for s in COLLISION.get(key, [])] if mirror else list(COLLISION.get(key, []))
        links[final] = {"mass": mass, "com": com, "shape": shape, "visual": visual, "collision": coll, "key": key}

    def add(table, prefix, mirror):
        for (jn, jt, parent, child, xyz, axis, lo, up, eff, vel) in table:
            if mirror:
                xyz = mirror_y(xyz)
                if axis in ("x", "z"):
                    lo, up = -up, -lo
            p = parent if parent in unsided else prefix + parent
            j = {"name": prefix + jn, "key": jn, "type": jt, "parent": p, "child": prefix + child, "xyz": xyz,
                 "rpy": FIXED_RPY.get(prefix + jn, (0.0, 0.0, 0.0)), "axis": axis, "lower": lo, "upper": up,
                 "effort": eff, "velocity": vel, "mimic": None, "side": prefix}
            if jn in MIMIC:
                m, mult, off = MIMIC[jn]
                j["mimic"] = (prefix + m, mult, off)
            if prefix + jn in FIXED_MIMIC:
                j["mimic"] = FIXED_MIMIC[prefix + jn]
            joints.append(j)
            add_links(child, prefix + child, mirror)

    links["base_link"] = None
    add(CENTER[:2], "", False)
    add(LEG, "left_", False)
    add(LEG, "right_", True)
    add(CENTER[2:], "", False)
    add(ARM, "left_", False)
    add(ARM, "right_", True)
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
    """(ixx, ixy, ixz, iyy, iyz, izz) about the CoM, as the URDF writes them."""
    m, shape = link["mass"], link["shape"]
    if shape[0] == "zero":
        return (0.0,) * 6
    if shape[0] == "box":
        a, b, c = shape[1:]
        d = [m / 12 * (b * b + c * c), m / 12 * (a * a + c * c), m / 12 * (a * a + b * b)]
    else:
        axis, r, h = shape[1:]
        radial, axial = m / 12 * (3 * r * r + h * h), m / 2 * r * r
        d = [axial if axis == ax else radial for ax in ("x", "y", "z")]
    d = [float("%.8g" % v) for v in d]
    if name in TRIANGLE_EPS:
        k = d.index(max(d))
        others = [d[i] for i in range(3) if i != k]
        d[k] = float("%.8g" % ((others[0] + others[1]) * (1.0 + TRIANGLE_EPS[name])))
    if name in MINUS_1E22:
        k = {"ixx": 0, "iyy": 1, "izz": 2}[MINUS_1E22[name]]
        others = [d[i] for i in range(3) if i != k]
        d = [others[0]] * 3  # a thin rod: the two transverse moments equal
        d[k] = -1e-22
        return (d[0], 0.0, 0.0, d[1], 0.0, d[2])  # no off-diagonal noise on a rod (it would not be a rod)
    xy, xz, yz = noise_offdiag(name)
    return (d[0], xy, xz, d[1], yz, d[2])


def matrix6(i6):
    ixx, ixy, ixz, iyy, iyz, izz = i6
    return ((ixx, ixy, ixz), (ixy, iyy, iyz), (ixz, iyz, izz))


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
# Kinematics (for the checks)
# ---------------------------------------------------------------------------------------------
def forward(joints, q):
    """World placement (R, p) of every link at joint values q (mimics from their masters)."""
    X = {"base_link": (IDENTITY, (0.0, 0.0, 0.0))}
    value = {}
    for j in joints:
        if j["type"] != "fixed":
            if j["mimic"]:
                m, mult, off = j["mimic"]
                value[j["name"]] = mult * value[m] + off
            else:
                value[j["name"]] = q.get(j["name"], 0.0)
    for j in joints:
        R, p = X[j["parent"]]
        Rj = mmul(R, rpy_matrix(j["rpy"]))
        pj = vadd(p, mvec(R, j["xyz"]))
        if j["type"] != "fixed":
            Rj = mmul(Rj, rot_axis(AXES[j["axis"]], value[j["name"]]))
        X[j["child"]] = (Rj, pj)
    return X


def shape_points(s):
    if s[0] == "box":
        c, size = s[1], s[2]
        return [vadd(c, (sx * size[0] / 2, sy * size[1] / 2, sz * size[2] / 2)) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    if s[0] == "sphere":
        return [vadd(s[1], (0.0, 0.0, s[2])), vadd(s[1], (0.0, 0.0, -s[2]))]
    return [v for tri in cylinder_triangles(s[1], s[2], s[3]) for v in tri]


# ---------------------------------------------------------------------------------------------
# Writers
# ---------------------------------------------------------------------------------------------
def mesh_uri(link):
    return "package://%s/meshes/%s.stl" % (PKG, link)


def write_link(name, link):
    if link is None:
        return '  <link name="%s"/>\n' % name
    i6 = inertia_of(name, link)
    out = ['  <link name="%s">\n' % name,
           '    <inertial>\n',
           '      <origin xyz="%s" rpy="0 0 0"/>\n' % vec(link["com"]),
           '      <mass value="%s"/>\n' % num(link["mass"]),
           '      <inertia ixx="%s" ixy="%s" ixz="%s" iyy="%s" iyz="%s" izz="%s"/>\n' % tuple(cad(v) for v in i6),
           '    </inertial>\n']
    if link["visual"]:
        material = MATERIAL.get(name, "dark" if "hand" in name else "white")
        out += ['    <visual>\n',
                '      <origin xyz="0 0 0" rpy="0 0 0"/>\n',
                '      <geometry>\n',
                '        <mesh filename="%s"/>\n' % mesh_uri(name),
                '      </geometry>\n',
                '      <material name="%s"/>\n' % material,
                '    </visual>\n']
    for c in link["collision"]:
        if c[0] == "mesh":
            origin, geom = (0.0, 0.0, 0.0), '<mesh filename="%s"/>' % mesh_uri(name)
        elif c[0] == "box":
            origin, geom = c[1], '<box size="%s"/>' % vec(c[2])
        else:
            origin, geom = c[1], '<sphere radius="%s"/>' % num(c[2])
        out += ['    <collision>\n',
                '      <origin xyz="%s" rpy="0 0 0"/>\n' % vec(origin),
                '      <geometry>\n',
                '        %s\n' % geom,
                '      </geometry>\n',
                '    </collision>\n']
    out.append('  </link>\n')
    return "".join(out)


def write_joint(j):
    out = ['  <joint name="%s" type="%s">\n' % (j["name"], j["type"]),
           '    <origin xyz="%s" rpy="%s"/>\n' % (vec(j["xyz"]), angles(j["rpy"])),
           '    <parent link="%s"/>\n' % j["parent"],
           '    <child link="%s"/>\n' % j["child"]]
    if j["type"] == "fixed":
        if j["name"] in ZERO_AXIS:
            out.append('    <axis xyz="0 0 0"/>\n')
        if j["name"] in ZERO_LIMIT:
            out.append('    <limit lower="0" upper="0" effort="0" velocity="0"/>\n')
        if j["mimic"]:
            out.append('    <mimic joint="%s" multiplier="%s" offset="%s"/>\n' % (j["mimic"][0], num(j["mimic"][1]), num(j["mimic"][2])))
        out.append('  </joint>\n')
        return "".join(out)
    out.append('    <axis xyz="%s"/>\n' % vec(AXES[j["axis"]]))
    out.append('    <limit lower="%s" upper="%s" effort="%s" velocity="%s"/>\n' % (num(j["lower"]), num(j["upper"]), num(j["effort"]), num(j["velocity"])))
    if j["mimic"]:
        out.append('    <mimic joint="%s" multiplier="%s" offset="%s"/>\n' % (j["mimic"][0], num(j["mimic"][1]), num(j["mimic"][2])))
    if j["key"] in DYNAMICS:
        out.append('    <dynamics damping="%s" friction="%s"/>\n' % tuple(num(v) for v in DYNAMICS[j["key"]]))
    if j["key"] in SAFETY:
        lo, up, kp, kv = SAFETY[j["key"]]
        if j["axis"] in ("x", "z") and j["side"] == "right_":
            lo, up = -up, -lo
        out.append('    <safety_controller soft_lower_limit="%s" soft_upper_limit="%s" k_position="%s" k_velocity="%s"/>\n'
                   % (num(lo), num(up), num(kp), num(kv)))
    out.append('  </joint>\n')
    return "".join(out)


def write_urdf(joints, links):
    parts = [
        '<?xml version="1.0" encoding="utf-8"?>\n',
        "<!-- Generated by models/g1_like/generate_urdf.py; do not edit by hand.\n"
        "     A Unitree-G1-like humanoid written from published figures and estimates (README.md), in the\n"
        "     conventions of real description packages: a massless base_link, CAD-style inertias, fixed joints\n"
        "     with axis/limit/mimic, mimic fingers, package:// meshes, transmission and gazebo blocks.\n"
        "     x forward, y left, z up; zero pose: straight legs, upper arms down, forearms forward. -->\n",
        '<robot name="%s">\n' % ROBOT,
        '  <mujoco>\n',
        '    <compiler meshdir="../meshes/" discardvisual="false"/>\n',
        '  </mujoco>\n',
        '  <material name="dark">\n',
        '    <color rgba="0.2 0.2 0.2 1"/>\n',
        '  </material>\n',
        '  <material name="white">\n',
        '    <color rgba="0.7 0.7 0.7 1"/>\n',
        '  </material>\n',
        write_link("base_link", None),
    ]
    for j in joints:
        parts.append(write_link(j["child"], links[j["child"]]))
        parts.append(write_joint(j))
    # What ROS packages carry and parsers ignore.
    for j in sorted((j for j in joints if j["type"] != "fixed" and not j["mimic"]), key=lambda j: j["name"]):
        base = j["name"][: -len("_joint")]
        parts += ['  <transmission name="%s_tran">\n' % base,
                  '    <type>transmission_interface/SimpleTransmission</type>\n',
                  '    <joint name="%s">\n' % j["name"],
                  '      <hardwareInterface>hardware_interface/EffortJointInterface</hardwareInterface>\n',
                  '    </joint>\n',
                  '    <actuator name="%s_motor">\n' % base,
                  '      <hardwareInterface>hardware_interface/EffortJointInterface</hardwareInterface>\n',
                  '      <mechanicalReduction>1</mechanicalReduction>\n',
                  '    </actuator>\n',
                  '  </transmission>\n']
    parts += ['  <gazebo>\n',
              '    <plugin name="gazebo_ros_control" filename="libgazebo_ros_control.so">\n',
              '      <robotNamespace>/%s</robotNamespace>\n' % ROBOT,
              '      <robotSimType>gazebo_ros_control/DefaultRobotHWSim</robotSimType>\n',
              '    </plugin>\n',
              '  </gazebo>\n']
    for foot in ("left_ankle_roll_link", "right_ankle_roll_link"):
        parts += ['  <gazebo reference="%s">\n' % foot,
                  '    <mu1>0.8</mu1>\n',
                  '    <mu2>0.8</mu2>\n',
                  '    <kp value="1000000.0"/>\n',
                  '    <kd value="100.0"/>\n',
                  '    <self_collide>1</self_collide>\n',
                  '  </gazebo>\n']
    parts += ['  <gazebo reference="imu_in_pelvis">\n',
              '    <sensor name="imu_sensor" type="imu">\n',
              '      <always_on>true</always_on>\n',
              '      <update_rate>500</update_rate>\n',
              '    </sensor>\n',
              '  </gazebo>\n',
              '</robot>\n']
    return "".join(parts)


def write_srdf(joints):
    actuated = [j["name"] for j in joints if j["type"] != "fixed" and not j["mimic"]]
    q = standing(joints)
    out = ['<?xml version="1.0" encoding="UTF-8"?>\n',
           "<!-- Generated by models/g1_like/generate_urdf.py; do not edit by hand. -->\n",
           '<robot name="%s">\n' % ROBOT,
           '  <virtual_joint name="root_joint" type="floating" parent_frame="world" child_link="base_link"/>\n']
    for side in ("left", "right"):
        out += ['  <group name="%s_leg">\n' % side,
                '    <chain base_link="pelvis" tip_link="%s_sole_link"/>\n' % side,
                '  </group>\n']
    out += ['  <group name="waist">\n', '    <joint name="waist_yaw_joint"/>\n', '  </group>\n']
    for side in ("left", "right"):
        out += ['  <group name="%s_arm">\n' % side,
                '    <chain base_link="torso_link" tip_link="%s_hand_palm_link"/>\n' % side,
                '  </group>\n',
                '  <group name="%s_hand">\n' % side]
        for f in ("thumb_0", "index_0", "middle_0"):
            out.append('    <joint name="%s_hand_%s_joint"/>\n' % (side, f))
        out.append('  </group>\n')
    out.append('  <group name="all_joints">\n')
    out += ['    <joint name="%s"/>\n' % n for n in actuated]
    out.append('  </group>\n')
    out.append('  <group_state name="standing" group="all_joints">\n')
    out += ['    <joint name="%s" value="%s"/>\n' % (n, num(q[n])) for n in actuated]
    out.append('  </group_state>\n')
    for side in ("left", "right"):
        out.append('  <end_effector name="%s_hand_ee" parent_link="%s_hand_palm_link" group="%s_hand" parent_group="%s_arm"/>\n'
                   % (side, side, side, side))
    for side in ("left", "right"):
        out.append('  <end_effector name="%s_foot" parent_link="%s_sole_link" group="%s_leg"/>\n' % (side, side, side))
    pairs = sorted(tuple(sorted((j["parent"], j["child"]))) for j in joints
                   if j["type"] != "fixed" and j["parent"] not in ("base_link",))
    out += ['  <disable_collisions link1="%s" link2="%s" reason="Adjacent"/>\n' % p for p in pairs]
    out.append('</robot>\n')
    return "".join(out)


def write_package_xml():
    return ('<?xml version="1.0"?>\n'
            '<!-- Generated by models/g1_like/generate_urdf.py; do not edit by hand. -->\n'
            '<package format="2">\n'
            '  <name>%s</name>\n'
            '  <version>0.1.0</version>\n'
            '  <description>A Unitree-G1-like humanoid (lexdyn test model, written from published figures; not the G1).</description>\n'
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
# Postures and checks
# ---------------------------------------------------------------------------------------------
def standing(joints):
    q = {}
    for j in joints:
        if j["type"] == "fixed" or j["mimic"]:
            continue
        v = STANDING[j["key"]]
        if j["side"] == "right_" and j["axis"] in ("x", "z"):
            v = -v
        q[j["name"]] = v
    return q


def sole_points(X, links, side):
    R, p = X[side + "_ankle_roll_link"]
    return [vadd(p, mvec(R, v)) for c in links[side + "_ankle_roll_link"]["collision"] for v in shape_points(c)]


def whole_com(X, links):
    m, h = 0.0, (0.0, 0.0, 0.0)
    for name, link in links.items():
        if link is None:
            continue
        R, p = X[name]
        m += link["mass"]
        h = vadd(h, vscale(vadd(p, mvec(R, link["com"])), link["mass"]))
    return m, vscale(h, 1.0 / m)


def checks(joints, links, meshes):
    moving = [j for j in joints if j["type"] != "fixed"]
    mimics = [j for j in moving if j["mimic"]]
    actuated = [j for j in moving if not j["mimic"]]
    fixed = [j for j in joints if j["type"] == "fixed"]
    assert len(moving) == 33 and len(mimics) == 4 and len(actuated) == 29, (len(moving), len(mimics))
    body = [j for j in actuated if "hand" not in j["name"]]
    assert len(body) == 27  # 12 legs + 1 waist + 14 arms; plus 2 one-DoF hands
    print("joints: %d moving (%d actuated: %d body + %d hand masters; %d mimic fingers), %d fixed, %d links"
          % (len(moving), len(actuated), len(body), len(actuated) - len(body), len(mimics), len(fixed), len(links)))

    mass = sum(l["mass"] for l in links.values() if l)
    assert abs(mass - PUBLISHED_MASS) < 1.0, mass
    legs = sum(l["mass"] for n, l in links.items() if l and any(k in n for k in ("hip", "knee", "ankle")))
    arms = sum(l["mass"] for n, l in links.items() if l and any(k in n for k in ("shoulder", "elbow", "wrist", "hand")))
    print("total mass: %.3f kg (published ~%.0f kg); legs %.3f, arms with hands %.3f, pelvis+torso+head+imu %.3f"
          % (mass, PUBLISHED_MASS, legs, arms, mass - legs - arms))

    X0 = forward(joints, {})
    sole_z = min(p[2] for p in sole_points(X0, links, "left") + sole_points(X0, links, "right"))
    R, p = X0["head_link"]
    head_top = max(vadd(p, mvec(R, v))[2] for s in links["head_link"]["visual"] for v in shape_points(s))
    height, pelvis = head_top - sole_z, X0["pelvis"][1][2] - sole_z
    assert abs(height - PUBLISHED_HEIGHT) < 0.01, height
    for side in ("left", "right"):
        assert abs(X0[side + "_sole_link"][1][2] - sole_z) < 1e-12  # the box's lowest face is the sole frame
    thigh = norm(vsub(X0["left_knee_link"][1], X0["left_hip_roll_link"][1]))
    calf = norm(vsub(X0["left_ankle_pitch_link"][1], X0["left_knee_link"][1]))
    assert abs(thigh + calf - PUBLISHED_LEG) < 0.01
    print("zero pose: height (head top to sole) %.4f m (published %.2f m); pelvis origin %.4f m above the soles; "
          "thigh %.3f + calf %.3f = %.3f m (published %.1f m)" % (height, PUBLISHED_HEIGHT, pelvis, thigh, calf, thigh + calf, PUBLISHED_LEG))

    q = standing(joints)
    assert sorted(q) == sorted(j["name"] for j in actuated)
    for j in actuated:
        assert j["lower"] < q[j["name"]] < j["upper"], j["name"]
    for j in mimics:
        m, mult, off = j["mimic"]
        v = mult * q.get(m, 0.0) + off
        assert j["lower"] < v < j["upper"], j["name"]
    X = forward(joints, q)
    for side in ("left", "right"):
        R = X[side + "_sole_link"][0]
        assert max(abs(R[i][k] - IDENTITY[i][k]) for i in range(3) for k in range(3)) < 1e-12, "feet not flat"
    sz = [X[s + "_sole_link"][1][2] for s in ("left", "right")]
    assert abs(sz[0] - sz[1]) < 1e-12
    pts = sole_points(X, links, "left") + sole_points(X, links, "right")
    _, com = whole_com(X, links)
    assert min(p[0] for p in pts) < com[0] < max(p[0] for p in pts), com
    print("standing: every joint inside its limits (knees %.2f rad, hip/ankle pitch %.2f rad), feet flat; pelvis %.4f m and "
          "CoM %.4f m above the soles, CoM x %.4f m within the soles' [%.3f, %.3f] m"
          % (q["left_knee_joint"], q["left_hip_pitch_joint"], X["pelvis"][1][2] - sz[0], com[2] - sz[0], com[0],
             min(p[0] for p in pts), max(p[0] for p in pts)))

    classes = {}
    for name, link in sorted(links.items()):
        if link is None:
            continue
        cls, m, excess = inertia_class(matrix6(inertia_of(name, link)))
        classes.setdefault(cls, []).append(name)
        if name in TRIANGLE_EPS:
            rel = excess / m[2]
            assert cls == "noise" and 0.001 <= rel <= 0.005, (name, cls, rel)
        elif name in MINUS_1E22:
            assert cls == "valid" and m[0] < 0.0, (name, cls, m)
        elif link["shape"][0] == "zero":
            assert cls == "zero"
        else:
            assert cls == "valid", (name, cls, m)
    print("inertias: %d valid, triangle inequality violated as rounding noise: %s; zero (point mass): %s; a -1e-22 moment: %s"
          % (len(classes.get("valid", [])), ", ".join("%s (%.2f %%)" % (n, 100 * TRIANGLE_EPS[n]) for n in sorted(TRIANGLE_EPS)),
             ", ".join(classes.get("zero", [])), ", ".join(sorted(MINUS_1E22))))
    big = max(len(b) for b in meshes.values())
    assert big < 8192
    print("meshes: %d binary STL files, %d to %d bytes" % (len(meshes), min(len(b) for b in meshes.values()), big))


def write_file(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(path, mode) as f:
        f.write(data)


def main():
    joints, links = build()
    meshes = {}
    for name in sorted(links):
        link = links[name]
        if link and link["visual"]:
            meshes[name + ".stl"] = stl_bytes("%s/meshes/%s.stl (generated by generate_urdf.py)" % (PKG, name),
                                              shape_triangles(link["visual"]))
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
