#!/usr/bin/env python3
"""rostest: sim.launch brings up the whole simulated system; e-stop first, then a trick.

Also the A1 wire of SDK 3.3.4 end to end: /joint_states from the mock's motor states through the
driver (standing angles, legs moving in the trick), and the status light: the LEDs the driver puts
in HighCmd, shown by the mock as /rbd_sim/led, red in EMERGENCY_STOP, the GUI's blue when idle.

The same stack runs the fault "ZED2 jumping 1 m" (test_fault_zed2_jump.py; the EKF reads the
ZED2 through that test's relay, started with the class before either test). The two run in the
order of RBD_TEST_SEED; each begins from its own known state: this one engages the e-stop when the
fault's walk ran first (the power-up state is the first state the node saw), the fault's walk
starts from the e-stop or an idle robot.
"""

import functools
import math
import os
import unittest

import rosnode
import rospkg
import rospy
import tf2_ros
import yaml
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState, PointCloud2
from std_msgs.msg import String
from std_srvs.srv import SetBool
from test_fault_zed2_jump import Zed2JumpFault, Zed2Relay
from visualization_msgs.msg import Marker

import rbd_testkit
from rbd_geometry.rotation import yaw_of
from rbd_testkit.ros import RosoutWatcher, run_rostest

EXPECTED_NODES = [
    "/mock_a1", "/rbd_a1_driver", "/os1_sim", "/zed2_sim", "/world", "/robot_state_publisher",
    "/rbd_controller", "/rbd_pos_controller", "/rbd_navigation", "/rbd_gestrec", "/rbd_bridge", "/rbd_lidar",
    "/joint_state_fallback", "/cloud_decimator",
]


# The kit's wait_for, ending early when ROS shuts down.
wait_for = functools.partial(rbd_testkit.wait_for, abort=rospy.is_shutdown)


def yaw_difference(a, b):
    """a - b wrapped to (-pi, pi]."""
    return math.atan2(math.sin(a - b), math.cos(a - b))


class SimSmoke(Zed2JumpFault, unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.z = Zed2Relay()  # before either test: the EKF fuses the relayed ZED2
        cls.first_state = None  # the power-up state: the first /rbd_controller/state the node sees

        def first(msg):
            if cls.first_state is None:
                cls.first_state = msg.data

        rospy.Subscriber("/rbd_controller/state", String, first)

    def setUp(self):
        self.truth = None
        self.state = ""
        self.states = []
        self.clouds = 0
        self.joints = None
        self.thighs = []
        self.led = None
        self.max_speed_while_estopped = 0.0
        rospy.Subscriber("/rbd_sim/ground_truth", Odometry, self.on_truth)
        rospy.Subscriber("/rbd_controller/state", String, self.on_state)
        rospy.Subscriber("/ouster/points", PointCloud2, self.on_cloud)
        rospy.Subscriber("/joint_states", JointState, self.on_joints)
        rospy.Subscriber("/rbd_sim/led", Marker, self.on_led)
        self.gesture = rospy.Publisher("/rbd_gestrec/gesture", String, queue_size=10)

    def on_truth(self, msg):
        self.truth = msg
        if self.state == "EMERGENCY_STOP":
            t = msg.twist.twist
            speed = max(math.hypot(t.linear.x, t.linear.y), abs(t.angular.z))
            self.max_speed_while_estopped = max(self.max_speed_while_estopped, speed)

    def on_state(self, msg):
        self.state = msg.data
        self.states.append(msg.data)

    def on_cloud(self, _msg):
        self.clouds += 1

    def on_joints(self, msg):
        if msg._connection_header.get("callerid") != "/rbd_a1_driver":
            return  # the standing-pose fallback (rbd_bringup) publishes here too while the driver is silent
        self.joints = msg
        self.thighs.append(msg.position[1])

    def on_led(self, msg):
        self.led = [(round(c.r * 255), round(c.g * 255), round(c.b * 255)) for c in msg.colors]

    def led_is(self, rgb):
        return self.led == [rgb] * 4

    def test_system(self):
        self.assertTrue(wait_for(lambda: self.truth is not None and self.state, 60.0), "no ground truth / state")
        self.assertEqual(self.first_state, "EMERGENCY_STOP", "power-up state must be EMERGENCY_STOP")
        if self.state != "EMERGENCY_STOP":  # the ZED2 fault's walk ran first: e-stop again (known state)
            self.assertTrue(wait_for(lambda: self.state == "WAITING_FOR_GESTURE", 90.0), self.states[-5:])
            rospy.wait_for_service("/rbd_controller/em_stop", 10.0)
            self.assertTrue(rospy.ServiceProxy("/rbd_controller/em_stop", SetBool)(True).success)
            self.assertTrue(wait_for(lambda: self.state == "EMERGENCY_STOP", 5.0), self.states[-5:])

        def missing():
            running = set(rosnode.get_node_names())
            return [n for n in EXPECTED_NODES if n not in running]

        self.assertTrue(wait_for(lambda: not missing(), 60.0, step=0.5), "nodes not running: %s" % missing())
        self.assertTrue(wait_for(lambda: self.clouds >= 3, 30.0), "no /ouster/points")

        buf = tf2_ros.Buffer()
        tf2_ros.TransformListener(buf)
        mount = buf.lookup_transform("base_link", "os_sensor", rospy.Time(0), rospy.Duration(10.0)).transform
        with open(os.path.join(rospkg.RosPack().get_path("rbd_description"), "config", "mounts.yaml")) as fh:
            xyz = yaml.safe_load(fh)["os_sensor"]["xyz"]
        t = mount.translation
        for got, want in zip((t.x, t.y, t.z), xyz):
            self.assertAlmostEqual(got, want, places=6)

        # SDK 3.3.4 motor states through the driver: the A1 standing (a1_description angles).
        self.assertTrue(wait_for(lambda: self.joints is not None, 10.0), "no /joint_states from rbd_a1_driver")
        self.assertEqual(list(self.joints.name[:3]), ["FR_hip_joint", "FR_thigh_joint", "FR_calf_joint"])
        for leg in range(4):
            self.assertTrue(0.7 <= self.joints.position[3 * leg + 1] <= 0.9, self.joints.position)
            self.assertTrue(-1.6 <= self.joints.position[3 * leg + 2] <= -1.4, self.joints.position)
        # Status light: red while e-stopped (the GUI's emergency colour).
        self.assertTrue(wait_for(lambda: self.led_is((0xC6, 0x28, 0x28)), 10.0), "LEDs not red: %s" % self.led)

        # A gesture while the e-stop is engaged must not move the robot. rbd_gestrec's own log line
        # proves the gesture arrived (a sleep alone would pass on a wrong topic name).
        rosout = RosoutWatcher()
        rosout.wait_connected("/rbd_gestrec", 30.0)
        self.assertTrue(wait_for(lambda: self.gesture.get_num_connections() > 0, 30.0), "nobody takes gestures")
        start = self.truth.pose.pose.position
        mark = rosout.mark()
        rbd_testkit.stays_unchanged(
            lambda: self.state,
            lambda: rosout.find("gesture 'spin' -> command", node="/rbd_gestrec", since=mark),
            2.0,
            send=lambda: self.gesture.publish(String("spin")),
            timeout=30.0,
            what="the controller's state",
            proof="rbd_gestrec taking the gesture",
        )
        moved = math.hypot(self.truth.pose.pose.position.x - start.x, self.truth.pose.pose.position.y - start.y)
        self.assertLess(moved, 0.005)
        self.assertLess(self.max_speed_while_estopped, 1e-3)
        self.assertEqual(self.state, "EMERGENCY_STOP")

        rospy.wait_for_service("/rbd_controller/em_stop", 10.0)
        self.assertTrue(rospy.ServiceProxy("/rbd_controller/em_stop", SetBool)(False).success)
        self.assertTrue(wait_for(lambda: self.state == "WAITING_FOR_GESTURE", 15.0), self.states)
        self.assertTrue(wait_for(lambda: self.led_is((0x15, 0x65, 0xC0)), 10.0), "LEDs not idle blue: %s" % self.led)

        # Show the spin gesture until the controller takes it (a collision stop may come and go
        # meanwhile), then watch the trick on ground truth.
        yaws = []  # relative to the yaw before the trick
        yaw0 = yaw_of(self.truth.pose.pose.orientation)
        def taken():  # (the gesture is shown from the predicate until the controller takes it)
            if self.state in ("GENERATING_PATH", "EXECUTING"):
                return True
            if self.state == "WAITING_FOR_GESTURE":
                self.gesture.publish(String("spin"))
            return False

        wait_for(taken, 30.0, 0.3)
        self.assertIn(self.state, ("GENERATING_PATH", "EXECUTING"), self.states)

        def back_waiting():
            yaws.append(yaw_difference(yaw_of(self.truth.pose.pose.orientation), yaw0))
            return self.state == "WAITING_FOR_GESTURE"

        del self.thighs[:]
        self.assertTrue(wait_for(back_waiting, 90.0), "trick did not finish: %s" % self.states[-5:])
        self.assertGreater(max(self.thighs) - min(self.thighs), 0.1, "the legs did not move in the trick")
        self.assertGreater(max(abs(y) for y in yaws), 2.8, "the robot never faced backwards during spin")
        self.assertLess(abs(yaws[-1]), 0.1)


if __name__ == "__main__":
    rospy.init_node("test_sim_smoke")
    run_rostest("rbd_bringup", "sim_smoke", SimSmoke)
