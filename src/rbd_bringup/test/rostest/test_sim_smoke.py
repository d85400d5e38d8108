#!/usr/bin/env python3
"""rostest: sim.launch brings up the whole simulated system; e-stop first, then a trick."""

import math
import os
import time
import unittest

import rosnode
import rospkg
import rospy
import rostest
import tf2_ros
import yaml
from nav_msgs.msg import Odometry
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import String
from std_srvs.srv import SetBool

from rbd_bringup import a1_monitor
from rbd_bringup.a1_monitor import yaw_of

EXPECTED_NODES = [
    "/mock_a1", "/rbd_a1_driver", "/os1_sim", "/zed2_sim", "/world", "/robot_state_publisher",
    "/rbd_controller", "/rbd_pos_controller", "/rbd_navigation", "/rbd_gestrec", "/rbd_bridge", "/rbd_lidar",
    "/joint_state_fallback", "/cloud_decimator",
]


def wait_for(predicate, timeout, step=0.05):
    return a1_monitor.wait_for(predicate, timeout, step, abort=rospy.is_shutdown)


class SimSmoke(unittest.TestCase):
    def setUp(self):
        self.truth = None
        self.state = ""
        self.states = []
        self.clouds = 0
        self.max_speed_while_estopped = 0.0
        rospy.Subscriber("/rbd_sim/ground_truth", Odometry, self.on_truth)
        rospy.Subscriber("/rbd_controller/state", String, self.on_state)
        rospy.Subscriber("/ouster/points", PointCloud2, self.on_cloud)
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

    def test_system(self):
        self.assertTrue(wait_for(lambda: self.truth is not None and self.state, 60.0), "no ground truth / state")
        self.assertEqual(self.state, "EMERGENCY_STOP", "power-up state must be EMERGENCY_STOP")

        def missing():
            running = set(rosnode.get_node_names())
            return [n for n in EXPECTED_NODES if n not in running]

        self.assertTrue(wait_for(lambda: not missing(), 60.0, step=0.5), "nodes not running: %s" % missing())
        self.assertTrue(wait_for(lambda: self.clouds >= 3, 30.0), "no /ouster/points")

        buf = tf2_ros.Buffer()
        tf2_ros.TransformListener(buf)
        mount = buf.lookup_transform("base_link", "os_sensor", rospy.Time(0), rospy.Duration(10.0)).transform
        with open(os.path.join(rospkg.RosPack().get_path("rbd_bringup"), "config", "mounts.yaml")) as fh:
            xyz = yaml.safe_load(fh)["os_sensor"]["xyz"]
        t = mount.translation
        for got, want in zip((t.x, t.y, t.z), xyz):
            self.assertAlmostEqual(got, want, places=6)

        # A gesture while the e-stop is engaged must not move the robot.
        start = self.truth.pose.pose.position
        for _ in range(10):
            self.gesture.publish(String("spin"))
            time.sleep(0.2)
        time.sleep(1.0)
        moved = math.hypot(self.truth.pose.pose.position.x - start.x, self.truth.pose.pose.position.y - start.y)
        self.assertLess(moved, 0.005)
        self.assertLess(self.max_speed_while_estopped, 1e-3)
        self.assertEqual(self.state, "EMERGENCY_STOP")

        rospy.wait_for_service("/rbd_controller/em_stop", 10.0)
        self.assertTrue(rospy.ServiceProxy("/rbd_controller/em_stop", SetBool)(False).success)
        self.assertTrue(wait_for(lambda: self.state == "WAITING_FOR_GESTURE", 15.0), self.states)

        # Show the spin gesture until the controller takes it (a collision stop may come and go
        # meanwhile), then watch the trick on ground truth.
        yaws = []
        deadline = time.monotonic() + 30.0
        while self.state not in ("GENERATING_PATH", "EXECUTING") and time.monotonic() < deadline:
            if self.state == "WAITING_FOR_GESTURE":
                self.gesture.publish(String("spin"))
            time.sleep(0.3)
        self.assertIn(self.state, ("GENERATING_PATH", "EXECUTING"), self.states)

        def back_waiting():
            yaws.append(yaw_of(self.truth.pose.pose.orientation))
            return self.state == "WAITING_FOR_GESTURE"

        self.assertTrue(wait_for(back_waiting, 90.0), "trick did not finish: %s" % self.states[-5:])
        self.assertGreater(max(abs(y) for y in yaws), 2.8, "the robot never faced backwards during spin")
        self.assertLess(abs(yaws[-1]), 0.1)


if __name__ == "__main__":
    rospy.init_node("test_sim_smoke")
    rostest.rosrun("rbd_bringup", "sim_smoke", SimSmoke)
