"""robot.launch (through split.launch) and laptop.launch brought up for real, with stand-in inputs.

One private master for the module. The robot's hardware is stood in for by rbd_sim: the mock A1
as the SDK's LCM server (its own LCM port) and the simulated OS1/ZED2 where the mounts file
(rbd_description) says; ouster-ros and zed-ros-wrapper by the recording stand-in packages (conftest.py), because
robot.launch runs with drivers:=true. split.launch starts robot.launch on the "robot" machine,
here this host (address 127.0.0.1, this user: roslaunch runs it locally). laptop.launch then runs
RViz under Xvfb against the same master.

Truth from outside: the leg kinematics below are written from unitree_ros a1_description
(hip joint at (+-0.1805, +-0.047, 0) about x, thigh joint 0.0838 m outboard about y, calf
0.2 m below about y, foot 0.2 m below), evaluated through robot_state_publisher and TF.
"""

import getpass
import math
import os
import socket
import subprocess

import numpy as np
import pytest
import rosgraph
import rospkg
import rospy
import tf2_ros
import yaml
from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState, PointCloud2
from std_msgs.msg import String

from rbd_msgs.msg import CollisionState
from rbd_testkit import RosEnv, free_port, stop_process, wait_for, wait_for_port

MOUNTS = os.path.join(rospkg.RosPack().get_path("rbd_description"), "config", "mounts.yaml")
NAMES = ["%s_%s_joint" % (leg, j) for leg in ("FR", "FL", "RR", "RL") for j in ("hip", "thigh", "calf")]
EXPECTED_NODES = {"/rbd_a1_driver", "/rbd_lidar", "/ekf_localization", "/map_correction", "/robot_state_publisher",
                  "/joint_state_fallback", "/cloud_decimator", "/rbd_controller", "/rbd_pos_controller",
                  "/rbd_navigation", "/rbd_gestrec", "/rbd_bridge", "/zed2/zed_node"}


def free_udp_port():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def rot_x(q):
    c, s = math.cos(q), math.sin(q)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(q):
    c, s = math.cos(q), math.sin(q)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def foot_in_base(leg, hip, thigh, calf):
    """a1_description forward kinematics of one leg [m]."""
    sx = 1.0 if leg[0] == "F" else -1.0
    sy = -1.0 if leg[1] == "R" else 1.0
    down = np.array([0.0, 0.0, -0.2])
    in_hip = np.array([0.0, sy * 0.0838, 0.0]) + rot_y(thigh).dot(down + rot_y(calf).dot(down))
    return np.array([sx * 0.1805, sy * 0.047, 0.0]) + rot_x(hip).dot(in_hip)


def start_xvfb():
    r, w = os.pipe()
    proc = subprocess.Popen(["Xvfb", "-displayfd", str(w), "-screen", "0", "800x600x24", "-nolisten", "tcp"],
                            pass_fds=(w,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    os.close(w)
    with os.fdopen(r, "rb") as fh:
        display = fh.readline().decode().strip()
    if not display:
        stop_process(proc)
        raise RuntimeError("Xvfb did not report a display")
    return proc, ":" + display


class Robot:
    """The running robot stack and what the test process sees of it."""

    def __init__(self, env, bridge_port):
        self.env = env
        self.bridge_port = bridge_port
        self.master = rosgraph.Master("/bringup_test", master_uri=env.env["ROS_MASTER_URI"])
        self.states = []
        self.lidar = []
        self.odom = []
        self.diag = []
        self.joint_senders = []
        rospy.Subscriber("/rbd_controller/state", String, lambda m: self.states.append(m.data))
        rospy.Subscriber("/rbd_lidar/state", CollisionState, self.lidar.append, queue_size=20)
        rospy.Subscriber("/rbd_a1_driver/odom", Odometry, self.odom.append, queue_size=5)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diag, queue_size=20)
        rospy.Subscriber("/joint_states", rospy.AnyMsg, self.on_joints, queue_size=100)
        self.tf = tf2_ros.Buffer()
        self.listener = tf2_ros.TransformListener(self.tf)

    def on_diag(self, msg):
        self.diag.extend((rospy.get_time(), s) for s in msg.status if s.name == "joint_state_fallback: joint states")

    def on_joints(self, msg):
        self.joint_senders.append((rospy.get_time(), msg._connection_header["callerid"]))

    def nodes(self):
        return {n for _, nodes in self.master.getSystemState()[1] for n in nodes} | {
            n for _, nodes in self.master.getSystemState()[0] for n in nodes}

    def subscribers(self, topic):
        return {n for t, nodes in self.master.getSystemState()[1] if t == topic for n in nodes}

    def translation(self, child):
        t = self.tf.lookup_transform("base_link", child, rospy.Time(0), rospy.Duration(5.0)).transform.translation
        return np.array([t.x, t.y, t.z])


@pytest.fixture(scope="module")
def robot(standin_path):
    env = RosEnv()
    env.env["ROS_PACKAGE_PATH"] = standin_path
    lcm_url = "udpm://239.255.76.67:%d?ttl=0" % free_udp_port()
    bridge_port = free_port()
    sim = os.path.join(subprocess.check_output(["rospack", "find", "rbd_sim"], universal_newlines=True).strip(),
                       "launch")
    try:
        # Stand-in inputs: the A1 behind its LCM server, the OS1 and the ZED2 where mounts.yaml says.
        # The A1 speaks SDK v3.3 (265 B HighState, no motor states): nobody sends joint angles, the
        # case the standing-pose fallback is for (with 3.3.4 the driver publishes the mock's).
        env.start(["roslaunch", os.path.join(sim, "mock_a1.launch"), os.path.join(sim, "sensors.launch"),
                   "driver:=false", "lcm_url:=" + lcm_url, "mounts:=" + MOUNTS, "publish_mount_tf:=false",
                   "lidar_columns:=512", "world:=lab", "sdk_layout:=3.3"])
        # A second roslaunch must find the first one's /run_id, or one of them refuses to run.
        master = rosgraph.Master("/bringup_test", master_uri=env.env["ROS_MASTER_URI"])
        assert wait_for(lambda: master.hasParam("/run_id"), 60.0, 0.1), "the input roslaunch did not start"
        env.start(["roslaunch", "rbd_bringup", "split.launch", "robot_address:=127.0.0.1",
                   "robot_user:=" + getpass.getuser(), "rviz:=false", "drivers:=true", "os1_hostname:=os1-standin",
                   "lcm_url:=" + lcm_url, "bridge_port:=%d" % bridge_port])
        env.use_in_this_process()
        rospy.init_node("bringup_test", anonymous=True, disable_signals=True)
        robot = Robot(env, bridge_port)
        # Every test starts with the whole robot side up, whichever runs first (Python nodes take
        # tens of seconds to start on a loaded 2-core machine).
        assert wait_for(lambda: EXPECTED_NODES <= robot.nodes(), 90.0, 0.5), EXPECTED_NODES - robot.nodes()
        yield robot
    finally:
        env.close()


def test_robot_launch_comes_up_in_emergency_stop_with_its_inputs_flowing(robot):
    assert EXPECTED_NODES <= robot.nodes(), EXPECTED_NODES - robot.nodes()
    assert wait_for(lambda: robot.states, 30.0)
    assert robot.states[0] == "EMERGENCY_STOP"
    # The driver hears the (mock) A1; the zone sees the (simulated) OS1 and is not stale.
    assert wait_for(lambda: robot.odom, 30.0), "no /rbd_a1_driver/odom: HighState not arriving"
    assert wait_for(lambda: len([s for s in robot.lidar if not s.stale and not s.error]) >= 3, 30.0)
    wait_for_port(robot.bridge_port, 30.0)
    # The mounts of the calibration file, published by the URDF.
    with open(MOUNTS) as fh:
        mounts = yaml.safe_load(fh)
    for frame in ("os_sensor", "zed2_camera_center", "collision_zone"):
        assert robot.translation(frame) == pytest.approx(np.array(mounts[frame]["xyz"]), abs=1e-6)
    # drivers:=true ran both driver launch files with our settings (values in test_launch_files.py).
    params = robot.master.getParam("/standin")
    assert params["ouster_ros"]["sensor"]["sensor_hostname"] == "os1-standin"
    assert params["ouster_ros"]["sensor"]["timestamp_mode"] == "TIME_FROM_ROS_TIME"
    assert params["zed_wrapper"]["zed2"]["publish_urdf"] == "false"
    assert robot.master.getParam("/zed2/zed_node/pos_tracking/publish_tf") is False
    assert robot.master.getParam("/rbd_pos_controller/profile") == "thesis_table2"


def test_legs_follow_joint_states_and_the_fallback_steps_aside(robot):
    # Before anyone sends joint angles the fallback shows the standing pose, and says so.
    assert wait_for(lambda: [s for _, s in robot.diag if s.level == 1], 20.0)
    assert wait_for(lambda: any(c == "/joint_state_fallback" for _, c in robot.joint_senders), 10.0)
    standing = robot.translation("FR_foot")
    assert standing[2] == pytest.approx(-0.26, abs=0.005)  # foot sphere (r 0.02) on the floor 0.28 m down

    pub = rospy.Publisher("/joint_states", JointState, queue_size=10)
    angles = {"hip": 0.2, "thigh": 0.8, "calf": -1.5}
    msg = JointState(name=NAMES, position=[angles[n.split("_")[1]] for n in NAMES])
    expected = foot_in_base("FR", angles["hip"], angles["thigh"], angles["calf"])
    me = rospy.get_name()

    def send_until(predicate, timeout):
        def sent_and_true():  # (the joint states are sent from the predicate until it holds)
            msg.header.stamp = rospy.Time.now()
            pub.publish(msg)
            return predicate()

        return wait_for(sent_and_true, timeout, 0.02)

    def foot_at_expected():
        try:
            return np.allclose(robot.translation("FR_foot"), expected, atol=1e-3)
        except tf2_ros.TransformException:
            return False

    assert send_until(foot_at_expected, 20.0), (robot.translation("FR_foot"), expected)
    # Our messages arrive (the foot moved, diagnostics name us); the fallback stays silent meanwhile.
    assert send_until(lambda: [s for _, s in robot.diag if s.level == 0 and me in s.message], 10.0)
    t0 = rospy.get_time()
    assert send_until(lambda: rospy.get_time() > t0 + 1.5, 5.0)
    senders = {c for t, c in robot.joint_senders if t > t0}
    assert me in senders and "/joint_state_fallback" not in senders
    rl = foot_in_base("RL", angles["hip"], angles["thigh"], angles["calf"])
    assert robot.translation("RL_foot") == pytest.approx(rl, abs=1e-3)

    # Silence: after its timeout (1 s) the fallback takes over again.
    t1 = rospy.get_time()
    assert wait_for(lambda: any(c == "/joint_state_fallback" and t > t1 for t, c in robot.joint_senders), 10.0)
    assert wait_for(lambda: np.allclose(robot.translation("FR_foot"), standing, atol=1e-3), 10.0)
    pub.unregister()


def test_laptop_rviz_reads_the_thinned_cloud(robot):
    assert "/cloud_decimator" not in robot.subscribers("/ouster/points")  # nobody watches yet: not reading
    xvfb, display = start_xvfb()
    rviz = None
    try:
        robot.env.env.update(DISPLAY=display, XDG_RUNTIME_DIR=robot.env.home, LIBGL_ALWAYS_SOFTWARE="1")
        rviz = robot.env.start(["roslaunch", "rbd_bringup", "laptop.launch"])
        assert wait_for(lambda: "/rviz_audience" in robot.subscribers("/ouster/points_decimated"), 60.0, 0.5)
        assert "/rviz_audience" not in robot.subscribers("/ouster/points")
        # The decimator now reads the full cloud, and its output is small. (It checks every 0.5 s
        # for a connected subscriber; the bound is liveness: rviz registered before its connection
        # to the decimator was up, and CI U's loaded run needed more than 10 s for that.)
        assert wait_for(lambda: "/cloud_decimator" in robot.subscribers("/ouster/points"), 60.0, 0.2)
        cloud = rospy.wait_for_message("/ouster/points_decimated", PointCloud2, timeout=10.0)
        assert cloud.header.frame_id == "os_sensor"
        assert cloud.point_step == 16 and 0 < cloud.width <= 32 * 256
        assert [f.name for f in cloud.fields] == ["x", "y", "z", "range"]
    finally:
        if rviz is not None:
            stop_process(rviz)
        stop_process(xvfb)
    # RViz gone: the decimator lets go of the full cloud again.
    assert wait_for(lambda: "/cloud_decimator" not in robot.subscribers("/ouster/points"), 10.0, 0.2)
