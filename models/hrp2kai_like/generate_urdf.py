#!/usr/bin/env python3
"""Writes hrp2kai_like.urdf (or, with --srdf, hrp2kai_like.srdf) from the tables below.

The tables are the model's source of truth; models/hrp2kai_like/README.md lists every figure
with its source code (D derived, J JVRC-1 figure, E estimated). Regenerate with
    python3 models/hrp2kai_like/generate_urdf.py > models/hrp2kai_like/hrp2kai_like.urdf
    python3 models/hrp2kai_like/generate_urdf.py --srdf > models/hrp2kai_like/hrp2kai_like.srdf
The SRDF (ROS's semantic description) holds the limbs as groups and the published half-sitting
posture as a group state, as a description package would; `lexdyn-harness robot init` reads it.
Inertias are diagonal about the CoM, from the primitive shape (box or z-axis cylinder).

With --heavy it writes hrp2kai_heavy.urdf instead: the same robot with every link's mass (and
inertia) and every joint's effort limit scaled by 90/65, a 90 kg humanoid with the same 0.216 x
0.140 m soles (models/hrp2kai_heavy/README.md):
    python3 models/hrp2kai_like/generate_urdf.py --heavy > models/hrp2kai_heavy/hrp2kai_heavy.urdf

With --weak-upper-body [S] it writes hrp2kai_weak.urdf: hrp2kai_heavy whose chest, head and arm
joints have TALOS's effort limits (UPPER_BODY_EFFORT below) times S (default 1), in the URDF, so
that both the plan and the simulated servos are limited (models/hrp2kai_weak/README.md):
    python3 models/hrp2kai_like/generate_urdf.py --weak-upper-body > models/hrp2kai_weak/hrp2kai_weak.urdf
"""
import sys

# Right side; the left side negates y and maps roll/yaw limits [l, u] -> [-u, -l].
# name, parent link, child link, axis, origin xyz, lower, upper, velocity, effort
LEG = [
    ("LEG_JOINT0", "WAIST", "LEG_LINK0", "z", (0, -0.105, 0), -0.524, 0.785, 5.0, 100.0),
    ("LEG_JOINT1", "LEG_LINK0", "LEG_LINK1", "x", (0, 0, 0), -0.785, 0.349, 5.0, 250.0),
    ("LEG_JOINT2", "LEG_LINK1", "LEG_LINK2", "y", (0, 0, 0), -2.094, 0.785, 6.0, 300.0),
    ("LEG_JOINT3", "LEG_LINK2", "LEG_LINK3", "y", (0, 0, -0.37), 0.0, 2.618, 7.0, 300.0),
    ("LEG_JOINT4", "LEG_LINK3", "LEG_LINK4", "y", (0, 0, -0.37), -1.484, 0.960, 7.0, 250.0),
    ("LEG_JOINT5", "LEG_LINK4", "LEG_LINK5", "x", (0, 0, 0), -0.611, 0.785, 5.0, 150.0),
]
CHEST_HEAD = [
    ("CHEST_JOINT0", "WAIST", "CHEST_LINK0", "z", (0, 0, 0.35), -0.785, 0.785, 4.0, 150.0),
    ("CHEST_JOINT1", "CHEST_LINK0", "CHEST_LINK1", "y", (0, 0, 0), -0.524, 1.047, 4.0, 250.0),
    ("HEAD_JOINT0", "CHEST_LINK1", "HEAD_LINK0", "z", (0, 0, 0.30), -1.222, 1.222, 5.0, 20.0),
    ("HEAD_JOINT1", "HEAD_LINK0", "HEAD_LINK1", "y", (0, 0, 0), -0.873, 1.047, 5.0, 20.0),
]
ARM = [
    ("ARM_JOINT0", "CHEST_LINK1", "ARM_LINK0", "y", (0, -0.25, 0.20), -3.142, 1.047, 4.0, 120.0),
    ("ARM_JOINT1", "ARM_LINK0", "ARM_LINK1", "x", (0, 0, 0), -1.745, 0.175, 4.0, 120.0),
    ("ARM_JOINT2", "ARM_LINK1", "ARM_LINK2", "z", (0, 0, 0), -1.571, 1.571, 4.0, 60.0),
    ("ARM_JOINT3", "ARM_LINK2", "ARM_LINK3", "y", (0, 0, -0.30), -2.531, 0.0, 4.5, 80.0),
    ("ARM_JOINT4", "ARM_LINK3", "ARM_LINK4", "z", (0, 0, 0), -1.920, 1.920, 3.5, 30.0),
    ("ARM_JOINT5", "ARM_LINK4", "ARM_LINK5", "y", (0, 0, -0.30), -1.571, 1.571, 3.5, 30.0),
    ("ARM_JOINT6", "ARM_LINK5", "ARM_LINK6", "x", (0, 0, 0), -1.920, 1.920, 3.5, 20.0),
    ("ARM_JOINT7", "ARM_LINK6", "ARM_LINK7", "y", (0.03, 0, -0.10), -0.35, 1.05, 3.0, 10.0),
]
# link: mass (kg), CoM (m), shape ("box", x, y, z) or ("cyl", radius, height along z)
LINKS = {
    "WAIST": (11.0, (0, 0, 0.06), ("box", 0.22, 0.30, 0.18)),
    "LEG_LINK0": (1.0, (0, 0, 0.02), ("cyl", 0.05, 0.10)),
    "LEG_LINK1": (1.2, (0, 0, 0), ("box", 0.10, 0.08, 0.08)),
    "LEG_LINK2": (3.8, (0, 0, -0.16), ("box", 0.12, 0.12, 0.37)),
    "LEG_LINK3": (2.8, (0, 0, -0.17), ("box", 0.11, 0.11, 0.37)),
    "LEG_LINK4": (0.7, (0, 0, 0), ("box", 0.08, 0.08, 0.06)),
    "LEG_LINK5": (1.5, (0, 0, -0.08), ("box", 0.216, 0.14, 0.05)),
    "CHEST_LINK0": (1.5, (0, 0, 0), ("cyl", 0.07, 0.08)),
    "CHEST_LINK1": (15.0, (-0.02, 0, 0.12), ("box", 0.26, 0.36, 0.40)),
    "HEAD_LINK0": (0.5, (0, 0, 0), ("cyl", 0.03, 0.06)),
    "HEAD_LINK1": (2.0, (0.02, 0, 0.10), ("box", 0.18, 0.16, 0.20)),
    "ARM_LINK0": (1.0, (0, 0, 0), ("cyl", 0.05, 0.10)),
    "ARM_LINK1": (0.8, (0, 0, 0), ("box", 0.08, 0.08, 0.08)),
    "ARM_LINK2": (1.6, (0, 0, -0.15), ("cyl", 0.05, 0.30)),
    "ARM_LINK3": (1.0, (0, 0, -0.05), ("cyl", 0.045, 0.10)),
    "ARM_LINK4": (0.8, (0, 0, -0.20), ("cyl", 0.04, 0.20)),
    "ARM_LINK5": (0.4, (0, 0, 0), ("box", 0.06, 0.06, 0.06)),
    "ARM_LINK6": (0.7, (0, 0, -0.08), ("box", 0.06, 0.08, 0.12)),
    "ARM_LINK7": (0.2, (0, 0, -0.04), ("box", 0.02, 0.03, 0.08)),
}
AXES = {"x": "1 0 0", "y": "0 1 0", "z": "0 0 1"}


# --heavy: masses and effort limits times HEAVY_SCALE (65 kg -> 90 kg).
HEAVY_SCALE = 90.0 / 65.0
SCALE = 1.0

# --weak-upper-body: the effort limits (N m) of the chest, head and arm joints, those of the joint
# of TALOS's public description (talos_reduced.urdf) in the same place; the legs keep hrp2kai_heavy's.
UPPER_BODY_EFFORT = {
    "CHEST_JOINT0": 78.0,    # torso_1_joint (yaw)
    "CHEST_JOINT1": 78.0,    # torso_2_joint (pitch)
    "HEAD_JOINT0": 4.0,      # head_2_joint (yaw)
    "HEAD_JOINT1": 8.0,      # head_1_joint (pitch)
    "ARM_JOINT0": 44.64,     # arm_*_1_joint (shoulder, first)
    "ARM_JOINT1": 22.32,     # arm_*_2_joint (shoulder abduction)
    "ARM_JOINT2": 17.86,     # arm_*_3_joint (upper arm yaw)
    "ARM_JOINT3": 17.86,     # arm_*_4_joint (elbow)
    "ARM_JOINT4": 3.0,       # arm_*_5_joint (wrist yaw)
    "ARM_JOINT5": 6.6,       # arm_*_6_joint (wrist)
    "ARM_JOINT6": 6.6,       # arm_*_7_joint (wrist)
    "ARM_JOINT7": 1.0,       # gripper_*_joint
}
UPPER_SCALE = None           # None: no override; else the factor on UPPER_BODY_EFFORT


def num(v):
    s = "%.6f" % v
    s = s.rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def inertia(mass, shape):
    if shape[0] == "box":
        a, b, c = shape[1:]
        return (mass / 12 * (b * b + c * c), mass / 12 * (a * a + c * c), mass / 12 * (a * a + b * b))
    r, h = shape[1:]
    ixx = mass / 12 * (3 * r * r + h * h)
    return (ixx, ixx, mass / 2 * r * r)


def geometry(shape):
    if shape[0] == "box":
        return '<box size="%s %s %s"/>' % tuple(num(v) for v in shape[1:])
    return '<cylinder radius="%s" length="%s"/>' % (num(shape[1]), num(shape[2]))


def link(name, key, mirror):
    mass, com, shape = LINKS[key]
    mass *= SCALE
    com = (com[0], -com[1] if mirror else com[1], com[2])
    ixx, iyy, izz = inertia(mass, shape)
    xyz = " ".join(num(v) for v in com)
    return (
        '  <link name="%s">\n'
        '    <inertial>\n'
        '      <origin xyz="%s" rpy="0 0 0"/>\n'
        '      <mass value="%s"/>\n'
        '      <inertia ixx="%s" ixy="0" ixz="0" iyy="%s" iyz="0" izz="%s"/>\n'
        '    </inertial>\n'
        '    <visual>\n'
        '      <origin xyz="%s" rpy="0 0 0"/>\n'
        '      <geometry>%s</geometry>\n'
        '    </visual>\n'
        '  </link>\n'
    ) % (name, xyz, num(mass), "%.9g" % ixx, "%.9g" % iyy, "%.9g" % izz, xyz, geometry(shape))


def joint(name, parent, child, axis, xyz, lower, upper, vel, effort, key=None):
    effort = effort * SCALE
    if UPPER_SCALE is not None and (key or name) in UPPER_BODY_EFFORT:
        effort = UPPER_BODY_EFFORT[key or name] * UPPER_SCALE
    return (
        '  <joint name="%s" type="revolute">\n'
        '    <parent link="%s"/>\n'
        '    <child link="%s"/>\n'
        '    <origin xyz="%s" rpy="0 0 0"/>\n'
        '    <axis xyz="%s"/>\n'
        '    <limit lower="%s" upper="%s" velocity="%s" effort="%s"/>\n'
        '  </joint>\n'
    ) % (name, parent, child, " ".join(num(v) for v in xyz), AXES[axis], num(lower), num(upper), num(vel), num(effort))


def side(table, prefix, mirror):
    """Joints and child links of one limb; prefix is R or L."""
    out = []
    for (jn, parent, child, axis, xyz, lo, up, vel, eff) in table:
        if mirror:
            xyz = (xyz[0], -xyz[1], xyz[2])
            if axis in ("x", "z"):
                lo, up = -up, -lo
        p = parent if parent in ("WAIST", "CHEST_LINK1") else prefix + parent
        out.append(joint(prefix + jn, p, prefix + child, axis, xyz, lo, up, vel, eff, key=jn))
        out.append(link(prefix + child, child, mirror))
    return out


# Published half-sitting posture (public Choreonoid sample project for HRP2KAI; README.md).
HALF_SITTING_LEG = (0, 0, -0.4538, 0.8727, -0.4189, 0)
HALF_SITTING_ARM = (0.2618, -0.1745, 0, -0.5236, 0, 0, 0, 0.349)  # right arm; the left negates roll and yaw


def srdf():
    out = ['<?xml version="1.0"?>\n',
           "<!-- Generated by models/hrp2kai_like/generate_urdf.py --srdf; do not edit by hand. -->\n",
           '<robot name="hrp2kai_like">\n']
    for prefix, name in (("R", "right"), ("L", "left")):
        out.append('  <group name="%s_leg"><chain base_link="WAIST" tip_link="%sLEG_LINK5"/></group>\n' % (name, prefix))
        out.append('  <group name="%s_arm"><chain base_link="CHEST_LINK1" tip_link="%sARM_LINK6"/></group>\n' % (name, prefix))
    out.append('  <group name="all">')
    for name in ("right_leg", "left_leg", "right_arm", "left_arm"):
        out.append('<group name="%s"/>' % name)
    out.append('<joint name="CHEST_JOINT0"/><joint name="CHEST_JOINT1"/><joint name="HEAD_JOINT0"/><joint name="HEAD_JOINT1"/></group>\n')
    out.append('  <group_state name="half_sitting" group="all">\n')
    for prefix in ("R", "L"):
        for k, v in enumerate(HALF_SITTING_LEG):
            out.append('    <joint name="%sLEG_JOINT%d" value="%s"/>\n' % (prefix, k, num(v)))
    for jn in ("CHEST_JOINT0", "CHEST_JOINT1", "HEAD_JOINT0", "HEAD_JOINT1"):
        out.append('    <joint name="%s" value="0"/>\n' % jn)
    for prefix, mirror in (("R", False), ("L", True)):
        for k, v in enumerate(HALF_SITTING_ARM):
            axis = ARM[k][3]
            out.append('    <joint name="%sARM_JOINT%d" value="%s"/>\n' % (prefix, k, num(-v if mirror and axis in ("x", "z") else v)))
    out.append("  </group_state>\n</robot>\n")
    return "".join(out)


def main():
    global SCALE, UPPER_SCALE
    args = sys.argv[1:]
    usage = "usage: generate_urdf.py [--srdf | --heavy | --weak-upper-body [SCALE]]"
    if args == ["--srdf"]:
        sys.stdout.write(srdf())
        return
    name = "hrp2kai_like"
    comment = "     An HRP-2Kai-like humanoid written from published facts and estimates, see README.md.\n"
    if args == ["--heavy"]:
        SCALE = HEAVY_SCALE
        name = "hrp2kai_heavy"
        comment = "     hrp2kai_like with masses, inertias and effort limits times 90/65 (90 kg); models/hrp2kai_heavy/README.md.\n"
    elif args[:1] == ["--weak-upper-body"] and len(args) <= 2:
        try:
            UPPER_SCALE = float(args[1]) if len(args) == 2 else 1.0
        except ValueError:
            sys.exit(usage)
        if not (UPPER_SCALE > 0 and UPPER_SCALE < float("inf")) or num(min(UPPER_BODY_EFFORT.values()) * UPPER_SCALE) == "0":
            sys.exit("generate_urdf.py: the upper body's effort scale must be > 0 and finite (every limit at least 1e-6 N m)")
        SCALE = HEAVY_SCALE
        name = "hrp2kai_weak"
        comment = ("     hrp2kai_heavy (90 kg) with the chest, head and arm effort limits of TALOS's public description\n"
                   "     (talos_reduced.urdf) times %s; models/hrp2kai_weak/README.md.\n" % num(UPPER_SCALE))
    elif args:
        sys.exit(usage)
    parts = [
        '<?xml version="1.0"?>\n',
        "<!-- Generated by models/hrp2kai_like/generate_urdf.py; do not edit by hand.\n"
        + comment +
        "     x forward, y left, z up; zero pose: straight legs, arms down, WAIST 0.845 m above the soles. -->\n",
        '<robot name="%s">\n' % name,
        link("WAIST", "WAIST", False),
    ]
    parts += side(LEG, "R", False)
    parts += side(LEG, "L", True)
    for (jn, parent, child, axis, xyz, lo, up, vel, eff) in CHEST_HEAD:
        parts.append(joint(jn, parent, child, axis, xyz, lo, up, vel, eff))
        parts.append(link(child, child, False))
    parts += side(ARM, "R", False)
    parts += side(ARM, "L", True)
    parts.append("</robot>\n")
    sys.stdout.write("".join(parts))


if __name__ == "__main__":
    main()
