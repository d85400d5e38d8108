"""Every launch file of rbd_bringup resolves, and passes what it should (no ROS master needed).

Parameters come from ``roslaunch --dump-params`` and the node/machine assignment from roslaunch's own
loader (``roslaunch.config.load_config_default``), i.e. as roslaunch itself reads the files.
Expected values come from their sources: the thesis' Table 2 (k_x 2.5 /s, +-0.3 m/s; k_y 2.0 /s,
+-0.12 m/s; k_alpha 1.0 /s, +-36 deg/s) and the real driver launch files' argument names
(conftest.py).
"""

import copy
import math
import os
import subprocess

import pytest
import roslaunch.config
import rospkg
import yaml

PKG = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LAUNCH = os.path.join(PKG, "launch")
#: the shipped calibration file, as the launch files find it (rbd_description)
MOUNTS = os.path.join(rospkg.RosPack().get_path("rbd_description"), "config", "mounts.yaml")


_DUMPS = {}


def dump_params(launch, *args, env=None):
    """{param: value} as roslaunch would set them (each launch/args/package path dumped once)."""
    key = (launch, args, (env or os.environ).get("ROS_PACKAGE_PATH"))
    if key not in _DUMPS:
        out = subprocess.run(["roslaunch", "--dump-params", os.path.join(LAUNCH, launch)] + list(args),  # noqa: UP022
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True, timeout=120,
                             env=env)
        assert out.returncode == 0, out.stderr + out.stdout
        _DUMPS[key] = yaml.safe_load(out.stdout)
    return copy.deepcopy(_DUMPS[key])


def load_config(launch, *args):
    return roslaunch.config.load_config_default([(os.path.join(LAUNCH, launch), list(args))], None, verbose=False)


def test_every_launch_file_is_covered_here():
    assert sorted(f for f in os.listdir(LAUNCH) if f.endswith(".launch")) == [
        "common.launch", "laptop.launch", "robot.launch", "sim.launch", "split.launch"]


def test_robot_launch_uses_the_thesis_table2_profile():
    p = dump_params("robot.launch")
    assert p["/rbd_pos_controller/profile"] == "thesis_table2"
    assert (p["/rbd_pos_controller/k_x"], p["/rbd_pos_controller/k_y"], p["/rbd_pos_controller/k_alpha"]) == (
        2.5, 2.0, 1.0)
    assert (p["/rbd_pos_controller/max_vx"], p["/rbd_pos_controller/max_vy"]) == (0.3, 0.12)
    assert p["/rbd_pos_controller/max_wz"] == pytest.approx(math.radians(36.0), abs=1e-6)
    assert p["/rbd_pos_controller/max_v_hold"] <= 0.12  # the sideways hold within Table 2's 0.12 m/s


def test_sim_launch_uses_the_simulator_tuned_profile():
    p = dump_params("sim.launch")
    assert p["/rbd_pos_controller/profile"] == "sim_tuned"
    assert (p["/rbd_pos_controller/k_x"], p["/rbd_pos_controller/k_y"], p["/rbd_pos_controller/k_alpha"]) == (
        3.0, 3.0, 3.0)
    assert p["/rbd_pos_controller/max_v_hold"] == 0.2
    # Same saturations as the robot.
    assert (p["/rbd_pos_controller/max_vx"], p["/rbd_pos_controller/max_vy"]) == (0.3, 0.12)


def test_robot_and_sim_share_the_mounts_file_and_the_zone_origin():
    mounts = MOUNTS
    with open(mounts) as fh:
        data = yaml.safe_load(fh)
    sim, robot = dump_params("sim.launch"), dump_params("robot.launch")
    assert sim["/robot_description"] == robot["/robot_description"]
    assert "from %s" % mounts in robot["/robot_description"]
    for p in (sim, robot):
        assert p["/rbd_lidar/zone_frame"] == "collision_zone"
    # The simulated sensors get the same file.
    for node, frame in (("os1_sim", "os_sensor"), ("zed2_sim", "zed2_camera_center")):
        for key in ("parent", "xyz", "rpy"):
            assert sim["/%s/mounts/%s/%s" % (node, frame, key)] == data[frame][key]
    assert sim["/os1_sim/publish_mount_tf"] is False  # the URDF publishes the mounts


def test_robot_launch_starts_no_driver_by_default():
    nodes = {n.name for n in load_config("robot.launch").nodes}
    assert not [n for n in nodes if n.startswith("os_") or "zed" in n]
    assert {"rbd_a1_driver", "rbd_lidar", "robot_state_publisher", "joint_state_fallback", "cloud_decimator",
            "rbd_controller", "rbd_bridge"} <= nodes


def test_drivers_true_passes_our_settings_to_both_drivers(standin_path):
    env = dict(os.environ, ROS_PACKAGE_PATH=standin_path)
    p = dump_params("robot.launch", "drivers:=true", "os1_hostname:=os-992011000121.local", "lidar_mode:=2048x10",
                    env=env)
    ouster = {k.rsplit("/", 1)[1]: v for k, v in p.items() if k.startswith("/standin/ouster_ros/sensor/")}
    assert {
        "ouster_ns": "ouster",  # -> /ouster/points, /ouster/imu
        "sensor_hostname": "os-992011000121.local",
        "lidar_mode": "2048x10",
        "timestamp_mode": "TIME_FROM_ROS_TIME",
        "point_type": "original",  # 48-byte points with the raw range field
        "organized": "true",
        "destagger": "true",
        "point_cloud_frame": "os_sensor",
        "sensor_frame": "os_sensor",
        "pub_static_tf": "true",
        "viz": "false",
    }.items() <= ouster.items()
    assert ouster["udp_dest"].strip() == ""  # left to the driver's auto-detection, as its default
    zed = {k.rsplit("/", 1)[1]: v for k, v in p.items() if k.startswith("/standin/zed_wrapper/zed2/")}
    assert {"camera_name": "zed2", "node_name": "zed_node", "camera_model": "zed2", "publish_urdf": "false",
            "base_frame": "base_link"}.items() <= zed.items()
    # The wrapper's common.yaml says true; ours wins: odom->base_link and map->odom are the EKF's.
    assert p["/zed2/zed_node/pos_tracking/publish_tf"] is False
    assert p["/zed2/zed_node/pos_tracking/publish_map_tf"] is False
    assert p["/zed2/zed_node/pos_tracking/pos_tracking_enabled"] is True  # the pose the EKF fuses
    assert "/zed2/zed2_description" not in p  # no second URDF with zed2_camera_center
    # Without drivers:=true nothing of either driver is loaded, even with the packages present.
    p = dump_params("robot.launch", env=env)
    assert not [k for k in p if k.startswith("/standin/") or k.startswith("/zed2/")]


def test_split_launch_runs_the_robot_on_the_jetson_and_rviz_on_the_laptop():
    cfg = load_config("split.launch", "robot_address:=192.0.2.10", "drivers:=false")
    machines = {n.name: n.machine_name for n in cfg.nodes}
    assert machines.pop("rviz_audience") == "laptop"
    assert set(machines.values()) == {"robot"}
    assert {"rbd_a1_driver", "rbd_lidar", "robot_state_publisher", "rbd_bridge"} <= set(machines)
    robot = cfg.machines["robot"]
    assert (robot.address, robot.user) == ("192.0.2.10", "unitree")
    rviz = [n for n in cfg.nodes if n.name == "rviz_audience"][0]
    assert rviz.args.endswith("rviz/audience_remote.rviz")
    # split.launch forwards robot.launch's arguments.
    p = dump_params("split.launch", "robot_address:=192.0.2.10", "bridge_port:=9191")
    assert p["/rbd_bridge/port"] == 9191
    assert p["/rbd_pos_controller/profile"] == "thesis_table2"


def test_laptop_launch_shows_the_thinned_cloud():
    cfg = load_config("laptop.launch")
    (rviz,) = cfg.nodes
    assert rviz.package == "rviz" and rviz.args.endswith("rviz/audience_remote.rviz")


def rviz_displays(name):
    with open(os.path.join(PKG, "rviz", name)) as fh:
        return yaml.safe_load(fh)["Visualization Manager"]["Displays"]


def topics(displays):
    return {d.get("Topic") or d.get("Marker Topic") for d in displays} - {None}


@pytest.mark.parametrize("view", ["audience", "developer"])
def test_robot_views_have_no_simulation_displays_and_sim_views_add_only_those(view):
    robot, sim = rviz_displays(view + ".rviz"), rviz_displays(view + "_sim.rviz")
    assert not [t for t in topics(robot) if t.startswith("/rbd_sim/")]
    extra = [d for d in sim if d not in robot]
    assert extra and all((d.get("Topic") or d.get("Marker Topic")).startswith("/rbd_sim/") for d in extra)
    assert [d for d in sim if d in robot] == robot  # the robot's view, unchanged, plus the simulator's


def test_remote_view_is_the_audience_view_on_the_thinned_cloud():
    full, remote = rviz_displays("audience.rviz"), rviz_displays("audience_remote.rviz")
    assert "/ouster/points" in topics(full) and "/ouster/points" not in topics(remote)
    assert topics(remote) == topics(full) - {"/ouster/points"} | {"/ouster/points_decimated"}
    assert any(d["Class"] == "rviz/RobotModel" for d in remote)
    assert not [t for t in topics(remote) if t.startswith("/rbd_sim/")]


@pytest.mark.parametrize("launch, args, view", [
    ("sim.launch", ["rviz:=true"], "audience_sim.rviz"),
    ("laptop.launch", [], "audience_remote.rviz"),
    ("split.launch", ["robot_address:=192.0.2.10"], "audience_remote.rviz"),
])
def test_rviz_views_of_the_launch_files_exist(launch, args, view):
    (rviz,) = [n for n in load_config(launch, *args).nodes if n.package == "rviz"]
    path = rviz.args.split("-d ", 1)[1]
    assert os.path.basename(path) == view and os.path.exists(path)
