"""The Unitree A1 as RViz and TF see it: dimensions, the 12 leg joints, sensor mounts -> URDF.

ROS-free. Debian ships no xacro, so the URDF is generated here from the robot's dimensions and
the calibration file ``config/mounts.yaml`` (every sensor mount, one place) and loaded into
``robot_description`` by the launch files (``python3 -m rbd_description.a1_model MOUNTS``, the
``a1_urdf`` command's ``main``: no rosrun package search at every launch);
robot_state_publisher then publishes the legs from ``/joint_states`` and the mounts as static
TFs. The simulator reads the same file, so a changed mount moves the simulated sensor too.

Dimensions are the ones of unitree_ros ``a1_description`` (``xacro/const.xacro``); joint names,
axes and the zero pose follow its conventions (zero = leg straight down, hip about x, thigh and
calf about y); joint limits are the SDK's (``a1_const.h``, see ../shared/INTERFACES.md §2).
"""

import math
import sys
import xml.etree.ElementTree as ET
from collections import OrderedDict, namedtuple
from typing import Dict, List, Mapping, Optional, Sequence, Tuple

#: Leg order of the SDK's motor arrays and of unitree_ros: front right, front left, rear right, rear left.
LEGS = ("FR", "FL", "RR", "RL")
#: Joints of one leg, hip to foot.
LEG_JOINTS = ("hip", "thigh", "calf")
#: The 12 joint names in SDK order (``FR_hip_joint``, ``FR_thigh_joint``, ...).
JOINT_NAMES = tuple("%s_%s_joint" % (leg, joint) for leg in LEGS for joint in LEG_JOINTS)

# Dimensions [m] (a1_description const.xacro).
TRUNK_SIZE = (0.267, 0.194, 0.114)  # length, width, height of the trunk box
LEG_OFFSET_X = 0.1805  # hip joint ahead of / behind the trunk centre
LEG_OFFSET_Y = 0.047  # hip joint left / right of the trunk centre
THIGH_OFFSET = 0.0838  # thigh joint outboard of the hip joint
THIGH_LENGTH = 0.2
CALF_LENGTH = 0.2
FOOT_RADIUS = 0.02
HIP_RADIUS = 0.046
HIP_LENGTH = 0.04
THIGH_SECTION = (0.0245, 0.034)  # width, height of the thigh box
CALF_SECTION = (0.016, 0.016)
#: Nominal standing height of base_link above the floor [m] (as rbd_sim and rbd_lidar assume).
NOMINAL_BASE_HEIGHT = 0.28

#: Joint limits [rad] of the SDK (a1_const.h): hip, thigh, calf.
JOINT_LIMITS = {"hip": (-0.802, 0.802), "thigh": (-1.05, 4.19), "calf": (-2.7, -0.916)}
JOINT_AXES = {"hip": "1 0 0", "thigh": "0 1 0", "calf": "0 1 0"}
JOINT_EFFORT = 33.5  # [N m], a1_description
JOINT_VELOCITY = 21.0  # [rad/s], a1_description

#: ZED2 optics (zed-ros-wrapper zed_macro.urdf.xacro, model zed2): stereo baseline and the
#: optical frames' offset. Our URDF carries the camera's own frames so that the wrapper can run
#: with ``publish_urdf:=false`` (its URDF would give zed2_camera_center a second parent).
ZED2_BASELINE = 0.12
ZED2_OPTICAL_OFFSET_X = -0.01
ZED2_SIZE = (0.03, 0.175, 0.03)
#: OS1 housing (Ouster OS1 datasheet: 85 mm diameter, 73.5 mm high without the cap).
OS1_RADIUS = 0.0425
OS1_HEIGHT = 0.0735

#: Mounts the launch files need: the frames the drivers publish into, and the body point the
#: LiDAR zone is measured from (rbd_lidar ~zone_frame).
REQUIRED_MOUNTS = ("os_sensor", "zed2_camera_center", "collision_zone")
#: Frames that belong to the robot model (a mount may not reuse them).
MODEL_FRAMES = frozenset(
    ["base_link"]
    + ["%s_%s" % (leg, part) for leg in LEGS for part in ("hip", "thigh", "calf", "foot")]
    + ["zed2_left_camera_frame", "zed2_left_camera_optical_frame", "zed2_right_camera_frame",
       "zed2_right_camera_optical_frame"]
)
#: Frames the drivers publish themselves: a mount there would give them a second parent.
DRIVER_FRAMES = frozenset(["os_lidar", "os_imu", "zed2_imu_link", "odom", "map"])

Mount = namedtuple("Mount", ["name", "parent", "xyz", "rpy"])
Mount.__doc__ = """A fixed transform parent -> name: xyz [m] and roll/pitch/yaw [rad] (URDF convention)."""


class MountError(ValueError):
    """The mounts file is malformed; the message names the entry and the key."""


def _vector(name: str, key: str, value: object) -> Tuple[float, float, float]:
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise MountError("%s.%s must be a list of 3 numbers, got %r" % (name, key, value))
    out = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(float(v)):
            raise MountError("%s.%s must hold 3 finite numbers, got %r" % (name, key, value))
        out.append(float(v))
    return (out[0], out[1], out[2])


def parse_mounts(data: object, source: str = "mounts") -> Dict[str, Mount]:
    """Validate the content of a mounts file and return its mounts by frame name.

    Args:
        data: the YAML document: ``{frame: {parent: FRAME, xyz: [x, y, z], rpy: [r, p, y]}}``.
        source: name used in error messages (the file).

    Returns:
        The mounts in file order (an OrderedDict).

    Raises:
        MountError: on any unknown key, missing or malformed value, unknown parent, loop, a
            frame of the robot model or of a driver, or a missing required mount.
    """
    if not isinstance(data, dict) or not data:
        raise MountError("%s: expected a mapping of frame names to mounts" % source)
    mounts: Dict[str, Mount] = OrderedDict()
    for name, entry in data.items():
        where = "%s: %s" % (source, name)
        if not isinstance(name, str) or not name or "/" in name or " " in name:
            raise MountError("%s: invalid frame name %r" % (source, name))
        if name in MODEL_FRAMES or name in DRIVER_FRAMES:
            raise MountError("%s: %s is a frame of the robot model or a driver, not a mount" % (where, name))
        if not isinstance(entry, dict):
            raise MountError("%s: expected {parent, xyz, rpy}, got %r" % (where, entry))
        unknown = sorted(set(entry) - {"parent", "xyz", "rpy"})
        if unknown:
            raise MountError("%s: unknown key(s) %s (allowed: parent, xyz, rpy)" % (where, unknown))
        missing = [k for k in ("parent", "xyz", "rpy") if k not in entry]
        if missing:
            raise MountError("%s: missing key(s) %s" % (where, missing))
        parent = entry["parent"]
        if not isinstance(parent, str) or not parent:
            raise MountError("%s.parent must be a frame name, got %r" % (where, parent))
        mounts[name] = Mount(name, parent, _vector(where, "xyz", entry["xyz"]), _vector(where, "rpy", entry["rpy"]))
    for m in mounts.values():
        if m.parent not in mounts and m.parent not in MODEL_FRAMES:
            raise MountError("%s: %s.parent %r is neither a robot frame nor another mount" % (source, m.name, m.parent))
        seen = {m.name}
        parent = m.parent
        while parent in mounts:
            if parent in seen:
                raise MountError("%s: the parents of %s form a loop" % (source, m.name))
            seen.add(parent)
            parent = mounts[parent].parent
    missing = [r for r in REQUIRED_MOUNTS if r not in mounts]
    if missing:
        raise MountError("%s: required mount(s) %s missing" % (source, missing))
    return mounts


def load_mounts(path: str) -> Dict[str, Mount]:
    """Read and validate a mounts YAML file (see :func:`parse_mounts`)."""
    import yaml

    with open(path) as fh:
        try:
            data = yaml.safe_load(fh)
        except yaml.YAMLError as e:
            raise MountError("%s: not valid YAML: %s" % (path, e)) from None
    return parse_mounts(data, path)


def standing_pose(base_height: float = NOMINAL_BASE_HEIGHT) -> Dict[str, float]:
    """Joint angles of the nominal standing pose: each foot under its thigh joint, body at base_height.

    Args:
        base_height: height of base_link above the floor [m].

    Returns:
        Angle [rad] per joint name (hip 0, thigh t, calf -2 t with 2 L cos t = height - foot radius).

    Raises:
        ValueError: if no such pose exists within the joint limits.
    """
    reach = (base_height - FOOT_RADIUS) / (THIGH_LENGTH + CALF_LENGTH)
    if not 0.0 < reach < 1.0:
        raise ValueError("no standing pose for a base height of %.3f m" % base_height)
    thigh = math.acos(reach)
    calf = -2.0 * thigh
    angles = {"hip": 0.0, "thigh": thigh, "calf": calf}
    for joint, value in angles.items():
        lo, hi = JOINT_LIMITS[joint]
        if not lo <= value <= hi:
            raise ValueError("standing %s angle %.3f rad outside the limits for %.3f m" % (joint, value, base_height))
    return {"%s_%s_joint" % (leg, j): angles[j] for leg in LEGS for j in LEG_JOINTS}


def foot_positions(angles: Mapping[str, float]) -> Dict[str, Tuple[float, float, float]]:
    """Foot centres in base_link [m] for the given joint angles (forward kinematics of this model).

    Args:
        angles: angle [rad] per joint name; missing joints count as 0.

    Returns:
        Foot centre per leg name.
    """
    out = {}
    for leg in LEGS:
        sx = 1.0 if leg[0] == "F" else -1.0
        sy = -1.0 if leg[1] == "R" else 1.0
        q1, q2, q3 = (float(angles.get("%s_%s_joint" % (leg, j), 0.0)) for j in LEG_JOINTS)
        # In the hip frame (after the hip roll), thigh and calf swing in the x-z plane.
        x = -THIGH_LENGTH * math.sin(q2) - CALF_LENGTH * math.sin(q2 + q3)
        z = -THIGH_LENGTH * math.cos(q2) - CALF_LENGTH * math.cos(q2 + q3)
        y = sy * THIGH_OFFSET
        # Hip roll about x.
        y, z = y * math.cos(q1) - z * math.sin(q1), y * math.sin(q1) + z * math.cos(q1)
        out[leg] = (sx * LEG_OFFSET_X + x, sy * LEG_OFFSET_Y + y, z)
    return out


def _f(v: float) -> str:
    return ("%.6f" % v).rstrip("0").rstrip(".") if v != 0 else "0"


def _xyz(values: Sequence[float]) -> str:
    return " ".join(_f(v) for v in values)


def _material(parent: ET.Element, name: str, rgba: Optional[str] = None) -> None:
    m = ET.SubElement(parent, "material", name=name)
    if rgba:
        ET.SubElement(m, "color", rgba=rgba)


def _link(robot: ET.Element, name: str, shapes: Sequence[Tuple[str, Dict[str, str], str, str, str]] = ()) -> None:
    """A link with visuals: (geometry tag, its attributes, origin xyz, origin rpy, material)."""
    link = ET.SubElement(robot, "link", name=name)
    for tag, attrs, xyz, rpy, material in shapes:
        vis = ET.SubElement(link, "visual")
        ET.SubElement(vis, "origin", xyz=xyz, rpy=rpy)
        geo = ET.SubElement(vis, "geometry")
        ET.SubElement(geo, tag, **attrs)
        _material(vis, material)


def _joint(robot: ET.Element, name: str, kind: str, parent: str, child: str, xyz: str, rpy: str = "0 0 0",
           axis: Optional[str] = None, limits: Optional[Tuple[float, float]] = None) -> None:
    j = ET.SubElement(robot, "joint", name=name, type=kind)
    ET.SubElement(j, "parent", link=parent)
    ET.SubElement(j, "child", link=child)
    ET.SubElement(j, "origin", xyz=xyz, rpy=rpy)
    if axis:
        ET.SubElement(j, "axis", xyz=axis)
    if limits:
        ET.SubElement(j, "limit", lower=_f(limits[0]), upper=_f(limits[1]), effort=_f(JOINT_EFFORT),
                      velocity=_f(JOINT_VELOCITY))


def robot_urdf(mounts: Mapping[str, Mount], source: str = "") -> str:
    """The URDF of the A1 with its legs and the given sensor mounts.

    Args:
        mounts: validated mounts (:func:`parse_mounts`).
        source: the mounts file, named in the header comment.

    Returns:
        The URDF document as a string.
    """
    robot = ET.Element("robot", name="a1")
    robot.append(ET.Comment(
        " Generated by rbd_description (a1_model.py) from %s: Unitree A1 from primitives with the dimensions of "
        "unitree_ros a1_description and the SDK joint limits; sensor mounts from the calibration file. "
        % (source or "a mounts file")))
    _material(robot, "trunk", "0.16 0.17 0.19 1")
    _material(robot, "leg", "0.55 0.56 0.6 1")
    _material(robot, "hip", "0.25 0.26 0.29 1")
    _material(robot, "foot", "0.08 0.08 0.08 1")
    _material(robot, "ouster", "0.78 0.79 0.82 1")
    _material(robot, "zed", "0.1 0.1 0.12 1")

    lx, ly, lz = TRUNK_SIZE
    _link(robot, "base_link", [("box", {"size": _xyz(TRUNK_SIZE)}, "0 0 0", "0 0 0", "trunk")])
    for leg in LEGS:
        sx = 1.0 if leg[0] == "F" else -1.0
        sy = -1.0 if leg[1] == "R" else 1.0
        hip, thigh, calf, foot = ("%s_%s" % (leg, p) for p in ("hip", "thigh", "calf", "foot"))
        # The hip motor is a cylinder along x at the joint; the thigh motor sits outboard on it.
        _link(robot, hip, [
            ("cylinder", {"radius": _f(HIP_RADIUS), "length": _f(HIP_LENGTH)}, "0 0 0", "0 1.570796 0", "hip"),
            ("cylinder", {"radius": _f(HIP_RADIUS * 0.9), "length": _f(HIP_LENGTH)},
             _xyz((0, sy * THIGH_OFFSET, 0)), "1.570796 0 0", "hip"),
        ])
        _joint(robot, hip + "_joint", "revolute", "base_link", hip, _xyz((sx * LEG_OFFSET_X, sy * LEG_OFFSET_Y, 0)),
               axis=JOINT_AXES["hip"], limits=JOINT_LIMITS["hip"])
        _link(robot, thigh, [("box", {"size": _xyz((THIGH_SECTION[1], THIGH_SECTION[0], THIGH_LENGTH))},
                              _xyz((0, 0, -THIGH_LENGTH / 2)), "0 0 0", "leg")])
        _joint(robot, thigh + "_joint", "revolute", hip, thigh, _xyz((0, sy * THIGH_OFFSET, 0)),
               axis=JOINT_AXES["thigh"], limits=JOINT_LIMITS["thigh"])
        _link(robot, calf, [("box", {"size": _xyz((CALF_SECTION[1], CALF_SECTION[0], CALF_LENGTH))},
                             _xyz((0, 0, -CALF_LENGTH / 2)), "0 0 0", "leg")])
        _joint(robot, calf + "_joint", "revolute", thigh, calf, _xyz((0, 0, -THIGH_LENGTH)),
               axis=JOINT_AXES["calf"], limits=JOINT_LIMITS["calf"])
        _link(robot, foot, [("sphere", {"radius": _f(FOOT_RADIUS)}, "0 0 0", "0 0 0", "foot")])
        _joint(robot, foot + "_fixed", "fixed", calf, foot, _xyz((0, 0, -CALF_LENGTH)))

    for m in mounts.values():
        shapes: List[Tuple[str, Dict[str, str], str, str, str]] = []
        if m.name == "os_sensor":  # the OS1 stands on os_sensor, its base
            shapes = [("cylinder", {"radius": _f(OS1_RADIUS), "length": _f(OS1_HEIGHT)},
                       _xyz((0, 0, OS1_HEIGHT / 2)), "0 0 0", "ouster")]
        elif m.name == "zed2_camera_center":
            shapes = [("box", {"size": _xyz(ZED2_SIZE)}, "0 0 0", "0 0 0", "zed")]
        _link(robot, m.name, shapes)
        _joint(robot, m.name + "_mount", "fixed", m.parent, m.name, _xyz(m.xyz), _xyz(m.rpy))

    # The ZED2's own frames below its centre (the wrapper's URDF, which we switch off).
    half_pi = math.pi / 2
    for side, sy in (("left", 1.0), ("right", -1.0)):
        frame = "zed2_%s_camera_frame" % side
        _link(robot, frame)
        _joint(robot, "zed2_%s_camera_joint" % side, "fixed", "zed2_camera_center", frame,
               _xyz((0, sy * ZED2_BASELINE / 2, 0)))
        optical = "zed2_%s_camera_optical_frame" % side
        _link(robot, optical)
        _joint(robot, "zed2_%s_camera_optical_joint" % side, "fixed", frame, optical,
               _xyz((ZED2_OPTICAL_OFFSET_X, 0, 0)), _xyz((-half_pi, 0, -half_pi)))

    _indent(robot)
    return '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode") + "\n"


def _indent(elem: ET.Element, level: int = 0) -> None:
    """Pretty-print in place (ElementTree.indent is Python 3.9+)."""
    pad = "\n" + "  " * level
    if len(elem):
        if not (elem.text or "").strip():
            elem.text = pad + "  "
        for child in elem:
            _indent(child, level + 1)
        if not (child.tail or "").strip():
            child.tail = pad
    if level and not (elem.tail or "").strip():
        elem.tail = pad


def main(argv: Sequence[str]) -> int:
    """The ``a1_urdf`` command: write the URDF for the mounts file ``argv[1]`` to stdout.

    Args:
        argv: the command line (program name, mounts file).

    Returns:
        0; 1 with a message naming the file, entry and key on a bad mounts file; 2 on bad usage.
    """
    if len(argv) != 2 or argv[1].startswith("-"):
        sys.stderr.write("usage: a1_urdf MOUNTS_YAML\n")
        return 2
    try:
        mounts = load_mounts(argv[1])
    except (OSError, MountError) as e:
        sys.stderr.write("a1_urdf: %s\n" % e)
        return 1
    sys.stdout.write(robot_urdf(mounts, argv[1]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
