"""rbd_description.a1_model and a1_urdf: the A1 URDF against the public facts, the mounts file's checks.

The expected values are written here from their sources, not taken from a1_model: dimensions of
unitree_ros a1_description (xacro/const.xacro: leg_offset_x 0.1805, leg_offset_y 0.047,
thigh_offset 0.0838, thigh_length 0.2, calf_length 0.2, foot_radius 0.02, trunk 0.267 x 0.194 x
0.114), joint names and axes of its leg.xacro (FR/FL/RR/RL x hip/thigh/calf, hip about x, thigh
and calf about y), limits of the SDK's a1_const.h (../shared/INTERFACES.md §2).
"""

import math
import os
import subprocess
import xml.etree.ElementTree as ET

import pytest
import yaml

from rbd_description import a1_model
from rbd_description.a1_model import MountError, load_mounts, parse_mounts, robot_urdf, standing_pose

PKG = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MOUNTS = os.path.join(PKG, "config", "mounts.yaml")
LEGS = {"FR": (1, -1), "FL": (1, 1), "RR": (-1, -1), "RL": (-1, 1)}
LIMITS = {"hip": (-0.802, 0.802), "thigh": (-1.05, 4.19), "calf": (-2.7, -0.916)}
AXES = {"hip": (1, 0, 0), "thigh": (0, 1, 0), "calf": (0, 1, 0)}


def floats(text):
    return tuple(float(v) for v in text.split())


def urdf_tree(path=MOUNTS):
    return ET.fromstring(robot_urdf(load_mounts(path), path))


def good_mounts():
    with open(MOUNTS) as fh:
        return yaml.safe_load(fh)


def test_twelve_revolute_joints_with_unitree_names_axes_limits_and_origins():
    root = urdf_tree()
    joints = {j.get("name"): j for j in root.findall("joint")}
    revolute = [n for n, j in joints.items() if j.get("type") == "revolute"]
    expected = ["%s_%s_joint" % (leg, part) for leg in ("FR", "FL", "RR", "RL") for part in ("hip", "thigh", "calf")]
    assert sorted(revolute) == sorted(expected)
    assert list(a1_model.JOINT_NAMES) == expected  # SDK motor order FR, FL, RR, RL x hip, thigh, calf
    for leg, (sx, sy) in LEGS.items():
        origins = {
            "hip": (sx * 0.1805, sy * 0.047, 0.0),
            "thigh": (0.0, sy * 0.0838, 0.0),
            "calf": (0.0, 0.0, -0.2),
        }
        parents = {"hip": "base_link", "thigh": leg + "_hip", "calf": leg + "_thigh"}
        for part in ("hip", "thigh", "calf"):
            j = joints["%s_%s_joint" % (leg, part)]
            assert j.find("parent").get("link") == parents[part]
            assert j.find("child").get("link") == "%s_%s" % (leg, part)
            assert floats(j.find("origin").get("xyz")) == pytest.approx(origins[part], abs=1e-9)
            assert floats(j.find("axis").get("xyz")) == AXES[part]
            lim = j.find("limit")
            assert (float(lim.get("lower")), float(lim.get("upper"))) == LIMITS[part]
        foot = joints[leg + "_foot_fixed"]
        assert foot.get("type") == "fixed"
        assert floats(foot.find("origin").get("xyz")) == pytest.approx((0, 0, -0.2))
        sphere = root.find("link[@name='%s_foot']/visual/geometry/sphere" % leg)
        assert float(sphere.get("radius")) == 0.02
    trunk = root.find("link[@name='base_link']/visual/geometry/box")
    assert floats(trunk.get("size")) == (0.267, 0.194, 0.114)


def test_mounts_from_the_file_are_fixed_joints_under_base_link():
    data = good_mounts()
    root = urdf_tree()
    joints = {j.find("child").get("link"): j for j in root.findall("joint")}
    for frame in ("os_sensor", "zed2_camera_center", "collision_zone"):
        j = joints[frame]
        assert j.get("type") == "fixed"
        assert j.find("parent").get("link") == data[frame]["parent"]
        assert floats(j.find("origin").get("xyz")) == pytest.approx(tuple(data[frame]["xyz"]))
        assert floats(j.find("origin").get("rpy")) == pytest.approx(tuple(data[frame]["rpy"]))
    # The ZED2's own frames (zed-ros-wrapper's zed_macro: baseline 0.12 m) hang below its centre,
    # each link has exactly one parent.
    left = joints["zed2_left_camera_frame"]
    assert left.find("parent").get("link") == "zed2_camera_center"
    assert floats(left.find("origin").get("xyz")) == pytest.approx((0, 0.06, 0))
    children = [j.find("child").get("link") for j in root.findall("joint")]
    assert len(children) == len(set(children))
    links = {link.get("name") for link in root.findall("link")}
    assert set(children) | {"base_link"} == links


def test_a_changed_mount_moves_only_that_frame(tmp_path):
    data = good_mounts()
    data["os_sensor"]["xyz"] = [0.0, 0.0, 0.07]
    path = tmp_path / "m.yaml"
    path.write_text(yaml.safe_dump(data))
    def origins(root):
        return {j.find("child").get("link"): floats(j.find("origin").get("xyz")) for j in root.findall("joint")}

    moved, orig = origins(urdf_tree(str(path))), origins(urdf_tree())
    assert moved["os_sensor"] == (0.0, 0.0, 0.07) != orig["os_sensor"]
    assert {k: v for k, v in moved.items() if k != "os_sensor"} == {k: v for k, v in orig.items() if k != "os_sensor"}


def test_standing_pose_puts_the_feet_on_the_floor_within_the_limits():
    pose = standing_pose(0.28)
    assert set(pose) == set(a1_model.JOINT_NAMES)
    for name, q in pose.items():
        lo, hi = LIMITS[name.split("_")[1]]
        assert lo <= q <= hi, name
    # Forward kinematics written out here: foot = thigh joint + R_y(t) (0,0,-0.2) + R_y(t+c) (0,0,-0.2).
    t, c = pose["FR_thigh_joint"], pose["FR_calf_joint"]
    x = -0.2 * math.sin(t) - 0.2 * math.sin(t + c)
    z = -0.2 * math.cos(t) - 0.2 * math.cos(t + c)
    assert x == pytest.approx(0.0, abs=1e-9)
    assert z - 0.02 == pytest.approx(-0.28, abs=1e-9)  # sphere bottom on the floor, 0.28 m below base_link
    assert a1_model.foot_positions(pose)["RL"] == pytest.approx((-0.1805, 0.047 + 0.0838, -0.26))
    with pytest.raises(ValueError):
        standing_pose(0.5)  # legs are 0.4 m long


@pytest.mark.parametrize("mutate, message", [
    (lambda d: d["os_sensor"].update(xyz=[0.0, 0.0]), "os_sensor.xyz"),
    (lambda d: d["os_sensor"].update(xyz=[0.0, float("nan"), 0.1]), "os_sensor.xyz"),
    (lambda d: d["zed2_camera_center"].update(rpy="0 0 0"), "zed2_camera_center.rpy"),
    (lambda d: d["os_sensor"].update(heigth=0.1), "unknown key(s) ['heigth']"),
    (lambda d: d["os_sensor"].pop("parent"), "missing key(s) ['parent']"),
    (lambda d: d["os_sensor"].update(parent="trunk"), "neither a robot frame nor another mount"),
    (lambda d: d.pop("collision_zone"), "required mount(s) ['collision_zone'] missing"),
    (lambda d: d.update(FR_foot={"parent": "base_link", "xyz": [0, 0, 0], "rpy": [0, 0, 0]}), "frame of the robot"),
    (lambda d: d.update(os_imu={"parent": "os_sensor", "xyz": [0, 0, 0], "rpy": [0, 0, 0]}), "frame of the robot"),
    (lambda d: d.update(a={"parent": "b", "xyz": [0, 0, 0], "rpy": [0, 0, 0]},
                        b={"parent": "a", "xyz": [0, 0, 0], "rpy": [0, 0, 0]}), "loop"),
])
def test_bad_mounts_are_refused_with_the_entry_and_key(mutate, message):
    data = good_mounts()
    mutate(data)
    with pytest.raises(MountError) as err:
        parse_mounts(data, "mounts.yaml")
    assert message in str(err.value)
    assert "mounts.yaml" in str(err.value)


def test_extra_mounts_may_hang_below_other_mounts():
    data = good_mounts()
    data["lidar_bracket"] = {"parent": "os_sensor", "xyz": [0, 0, -0.01], "rpy": [0, 0, 0]}
    assert parse_mounts(data)["lidar_bracket"].parent == "os_sensor"


def test_a1_urdf_command_line(tmp_path):
    out = subprocess.run(["rosrun", "rbd_description", "a1_urdf", MOUNTS], stdout=subprocess.PIPE,  # noqa: UP022 (3.6)
                         stderr=subprocess.PIPE, universal_newlines=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert ET.fromstring(out.stdout.split("\n", 1)[1]).get("name") == "a1"
    bad = tmp_path / "bad.yaml"
    bad.write_text("os_sensor: {parent: base_link, xyz: [0, 0], rpy: [0, 0, 0]}\n")
    out = subprocess.run(["rosrun", "rbd_description", "a1_urdf", str(bad)], stdout=subprocess.PIPE,  # noqa: UP022 (3.6)
                         stderr=subprocess.PIPE, universal_newlines=True, timeout=60)
    assert out.returncode == 1
    assert "bad.yaml: os_sensor.xyz must be a list of 3 numbers" in out.stderr
    assert out.stdout == ""
