#!/usr/bin/env python3
"""rostest of the rbd_lidar node without the simulator: synthetic ouster-ros clouds in, every output checked.

This node publishes the clouds (10 Hz) and provides /rbd_controller/collision.
"""

import math
import os
import sys
import threading
import time
import unittest

import dynamic_reconfigure.client
import rosgraph
import rospy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import Imu, LaserScan, PointCloud2
from std_msgs.msg import Float32
from std_srvs.srv import SetBool, SetBoolResponse
from visualization_msgs.msg import Marker

import rbd_testkit
from rbd_msgs.msg import CollisionState
from rbd_testkit.ros import run_rostest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import synthetic_cloud  # noqa: E402

from rbd_geometry.rotation import rpy_to_quat

PERIOD = 0.1


class SyntheticLidarTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("synthetic_lidar_test")
        cls.lock = threading.Lock()
        cls.calls = []  # (wall time, data)
        cls.states = []
        cls.scans = []
        cls.critical = []
        cls.slices = []
        cls.speed = []
        cls.markers = []
        cls.logs = []
        cls.mode = "clear"
        cls.seq_stamps = {}
        cls.service = rospy.Service("/rbd_controller/collision", SetBool, cls.on_call)
        rospy.Subscriber("/rbd_lidar/state", CollisionState, cls.store("states"), queue_size=100)
        rospy.Subscriber("/scan", LaserScan, cls.store("scans"), queue_size=10)
        rospy.Subscriber("/rbd_lidar/collision_points", PointCloud2, cls.store("critical"), queue_size=10)
        rospy.Subscriber("/rbd_lidar/slice", PointCloud2, cls.store("slices"), queue_size=10)
        rospy.Subscriber("/rbd_lidar/speed_scale", Float32, cls.store("speed"), queue_size=100)
        rospy.Subscriber("/rbd_lidar/zone_marker", Marker, cls.store("markers"), queue_size=10)
        rospy.Subscriber("/rosout", Log, cls.store("logs"), queue_size=200)
        cls.pub = rospy.Publisher("/ouster/points", PointCloud2, queue_size=5)
        cls.clear_cloud = synthetic_cloud.make_cloud(rospy.Time(0))
        cls.person_cloud = synthetic_cloud.make_cloud(rospy.Time(0), person=(0.5, 0.0))
        # Person surface 0.8 m ahead: outside the 0.7 m zone, inside it when walking at 0.3 m/s.
        cls.near_cloud = synthetic_cloud.make_cloud(rospy.Time(0), person=(1.0, 0.0))
        # Attentive sitting: nose up 15 deg (ROS pitch -15 deg), body lowered: sensor 0.33 m above
        # the floor (the node assumes base_height 0.28 + mount 0.10 cos 15 deg = 0.377 m).
        cls.pitch = math.radians(-15.0)
        cls.tilted_cloud = synthetic_cloud.make_cloud(rospy.Time(0), pitch=cls.pitch, height=0.33)
        cls.cmd_pub = rospy.Publisher("/cmd_vel", Twist, queue_size=5)
        cls.odom_pub = rospy.Publisher("/rbd_a1_driver/odom", Odometry, queue_size=5)
        cls.imu_pub = rospy.Publisher("/ouster/imu", Imu, queue_size=20)
        cls.cmd = None
        cls.odom = None
        cls.imu = None
        cls.published = []  # (stamp, mode)
        cls.timer = rospy.Timer(rospy.Duration(PERIOD), cls.tick)

    @classmethod
    def on_call(cls, req):
        with cls.lock:
            cls.calls.append((time.monotonic(), req.data))
        return SetBoolResponse(success=True, message="")

    @classmethod
    def store(cls, name):
        def cb(msg):
            with cls.lock:
                getattr(cls, name).append(msg)
        return cb

    @classmethod
    def tick(cls, _event):
        with cls.lock:
            mode = cls.mode
        if mode == "silent":
            return
        stamp = rospy.Time.now()
        if cls.cmd is not None:
            cls.cmd_pub.publish(cls.cmd)
        if cls.odom is not None:
            cls.odom.header.stamp = stamp
            cls.odom_pub.publish(cls.odom)
        if cls.imu is not None:
            cls.imu.header.stamp = stamp
            cls.imu_pub.publish(cls.imu)
        if mode == "clear":
            msg = cls.clear_cloud
        elif mode == "person":
            msg = cls.person_cloud
        elif mode == "near":
            msg = cls.near_cloud
        elif mode == "tilted":
            msg = cls.tilted_cloud
        else:
            msg = synthetic_cloud.malformed(stamp, mode)
        msg.header.stamp = stamp
        with cls.lock:
            cls.published.append((stamp, mode))
        cls.pub.publish(msg)

    def state_of_next(self, mode, count=1):
        """States of the next `count` clouds published in `mode` (waits for them)."""
        with self.lock:
            n_pub = len(self.published)
        self.wait_for(lambda: sum(1 for _, m in self.published[n_pub:] if m == mode) >= count, 5.0, mode)
        with self.lock:
            stamps = [s for s, m in self.published[n_pub:] if m == mode][:count]
        return [self.state_for(s) for s in stamps]

    def settle(self, mode, collision, scans=5):
        """Publish `mode` until the collision state has been `collision` for `scans` scans."""
        self.set_mode(mode)
        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline:
            if all(s.collision == collision for s in self.state_of_next(mode, scans)):
                return
        self.fail("state never settled to collision=%s in mode %s" % (collision, mode))

    def stays_one_call(self, n_calls, n_states):
        """After the first collision service call since ``n_calls``, no other for ``n_states`` more states."""
        self.wait_for(lambda: self.calls[n_calls:], 5.0, "a collision service call")
        n = len(self.states)
        rbd_testkit.stays_unchanged(lambda: [d for _, d in self.calls[n_calls:]],
                                    lambda: len(self.states) >= n + n_states, hold=0.0, timeout=10.0,
                                    what="collision service calls", proof="%d more states" % n_states)

    def set_mode(self, mode):
        with self.lock:
            type(self).mode = mode
            return len(self.published), len(self.states), len(self.calls)

    def wait_for(self, predicate, timeout, what):
        def locked():
            with self.lock:
                return predicate()

        rbd_testkit.wait_for(locked, timeout, 0.02, what=what, abort=rospy.is_shutdown)

    def state_for(self, stamp, timeout=3.0):
        found = []

        def pred():
            found[:] = [s for s in self.states if s.header.stamp == stamp]
            return bool(found)

        self.wait_for(pred, timeout, "the state of the cloud stamped %s" % stamp)
        return found[0]

    def setUp(self):
        """Known state for the odom-attitude tests, whatever ran before: clear clouds, no cmd_vel, odom
        or IMU, and the node reporting clear (as after its start-up)."""
        type(self).cmd = type(self).odom = type(self).imu = None
        if rospy.get_param("~attitude", "odom") != "odom":
            return  # the IMU run's single test sets up its own state
        self.cmd_pub.publish(Twist())
        self.set_mode("clear")
        self.wait_for(lambda: self.states and not self.states[-1].collision and self.calls
                      and not self.calls[-1][1], 20.0, "clear state and a data=false call")

    def test_node(self):
        if rospy.get_param("~attitude", "odom") != "odom":
            self.skipTest("odom attitude run only")
        self.run_node()

    def test_wiring(self):
        if rospy.get_param("~attitude", "odom") != "odom":
            self.skipTest("odom attitude run only")
        self.run_wiring()

    def test_imu_attitude(self):
        """attitude_source imu: the tilted floor is rejected once the LiDAR's IMU reports the tilt."""
        if rospy.get_param("~attitude", "odom") != "imu":
            self.skipTest("imu attitude run only")
        # Wait until the node is up and answers the clouds.
        self.set_mode("tilted")
        self.wait_for(lambda: {s.header.stamp for s in self.states} & {s for s, _ in self.published}, 20.0,
                      "the node to process clouds")
        self.settle("tilted", True)
        st = self.state_of_next("tilted")[0]
        self.assertGreater(st.points[CollisionState.BACK], 5)
        imu = Imu()
        imu.header.frame_id = "os_imu"
        # Specific force +g up, seen in the sensor frame pitched by self.pitch (rotation about y).
        imu.linear_acceleration.x = -math.sin(self.pitch) * 9.81
        imu.linear_acceleration.z = math.cos(self.pitch) * 9.81
        imu.orientation_covariance[0] = -1.0
        type(self).imu = imu
        self.settle("tilted", False)
        # IMU lost: back to the fixed (level) assumption, the floor triggers again (fail-safe side).
        type(self).imu = None
        self.settle("tilted", True)

    def run_node(self):
        # 1. Clear room: the collision (initial / stale at start-up) clears; all outputs flow.
        self.wait_for(lambda: self.states and not self.states[-1].collision and self.calls
                      and not self.calls[-1][1], 20.0, "clear state and a data=false call")
        with self.lock:
            scan = self.scans[-1]
            self.assertEqual(len(scan.ranges), 512)
            self.assertTrue(self.slices and self.slices[-1].width > 400)
            self.assertTrue(self.markers and len(self.markers[-1].points) == 24)
            self.assertEqual(self.critical[-1].width, 0)
            self.assertAlmostEqual(self.speed[-1].data, 1.0, places=3)
            self.assertFalse(self.states[-1].stale)
            self.assertEqual(self.states[-1].error, "")
        # Room walls at 3 m: the scan sees them ahead.
        ahead = scan.ranges[int((0.0 - scan.angle_min) / scan.angle_increment)]
        self.assertAlmostEqual(ahead, 3.0, delta=0.03)

        # 2. A person 0.5 m ahead: collision on the first scan containing it, one service call.
        n_pub, _, n_calls = self.set_mode("person")
        self.wait_for(lambda: any(m == "person" for _, m in self.published[n_pub:]), 2.0, "a person cloud")
        with self.lock:
            first = next(s for s, m in self.published[n_pub:] if m == "person")
        st = self.state_for(first)
        self.assertTrue(st.collision)
        self.assertGreater(st.points[CollisionState.FRONT], 5)
        self.assertLess(st.min_distance[CollisionState.FRONT], 0.35)
        self.assertEqual(st.speed_scale, 0.0)
        # one call while the person stays: proven over 15 more states (1.5 s of clouds), not a sleep
        self.stays_one_call(n_calls, 15)
        with self.lock:
            after = [d for _, d in self.calls[n_calls:]]
            self.assertEqual(after, [True])
            self.assertGreater(self.critical[-1].width, 5)

        # 3. Removed: clear after exactly 3 clear scans (hysteresis), one data=false call.
        n_pub, _, n_calls = self.set_mode("clear")
        self.wait_for(lambda: sum(1 for _, m in self.published[n_pub:] if m == "clear") >= 4, 3.0, "clear clouds")
        with self.lock:
            clear_stamps = [s for s, m in self.published[n_pub:] if m == "clear"][:4]
        flags = [self.state_for(s).collision for s in clear_stamps]
        self.assertEqual(flags, [True, True, False, False])
        self.stays_one_call(n_calls, 10)
        with self.lock:
            self.assertEqual([d for _, d in self.calls[n_calls:]], [False])

        # 4. Malformed clouds: collision with an error each time, node alive, then recovery.
        # Each kind is sent 4 times in a row but logged once (throttled per kind).
        with self.lock:
            n_logs = len(self.logs)
        kinds = ("no_range", "point_step", "height", "truncated", "nan", "empty")
        for kind in kinds:
            n_pub, _, _ = self.set_mode(kind)
            self.wait_for(lambda n=n_pub, k=kind: sum(1 for _, m in self.published[n:] if m == k) >= 4, 3.0, kind)
            with self.lock:
                stamp = next(s for s, m in self.published[n_pub:] if m == kind)
            st = self.state_for(stamp)
            self.assertTrue(st.collision, kind)
            self.assertNotEqual(st.error, "", kind)

        def rejected_logs():
            with self.lock:
                return [lg.msg for lg in self.logs[n_logs:] if lg.name == "/rbd_lidar" and "cloud rejected" in lg.msg]

        # One line per kind: counted in step 5, at /rbd_lidar's stale line (see there).
        n_pub, n_states, _ = self.set_mode("clear")
        self.wait_for(lambda: any(not s.collision for s in self.states[n_states:]), 5.0, "recovery after bad input")
        self.wait_for(lambda: self.calls[-1][1] is False, 3.0, "data=false call after recovery")

        # 5. Silence: stale after 3 periods => collision, the service is told.
        _, n_states, n_calls = self.set_mode("silent")
        t0 = time.monotonic()
        self.wait_for(lambda: any(s.stale and s.collision for s in self.states[n_states:]), 3.0, "stale state")
        self.assertLess(time.monotonic() - t0, 1.5)
        # /rbd_lidar logs the stale line after it judged every malformed cloud of step 4, and its
        # /rosout lines come in order on one connection: once this line is in, every rejection
        # line is too (a second line of a kind, had the throttle failed, among them).
        self.wait_for(lambda: any(lg.name == "/rbd_lidar" and "collision (stale)" in lg.msg
                                  for lg in self.logs[n_logs:]), 5.0, "/rbd_lidar's stale line on /rosout")
        rejected = rejected_logs()
        self.assertEqual(len(rejected), len(kinds), [(lg.name, lg.msg[:40]) for lg in self.logs[-10:]])
        self.assertEqual(len({m.split(": ")[2] for m in rejected}), len(kinds), rejected)
        self.wait_for(lambda: [d for _, d in self.calls[n_calls:]] == [True], 3.0, "data=true call when stale")
        with self.lock:
            self.assertEqual(self.speed[-1].data, 0.0)


    def run_wiring(self):
        """cmd_vel growth, dynamic_reconfigure, odom attitude, absent service."""
        # Velocity-aware zone: 0.8 m ahead is clear at rest, critical when walking at 0.3 m/s.
        self.settle("near", False)
        type(self).cmd = Twist()
        self.cmd.linear.x = 0.3
        self.settle("near", True)
        st = self.state_of_next("near")[0]
        self.assertGreater(st.points[CollisionState.FRONT], 5)
        type(self).cmd = None
        self.cmd_pub.publish(Twist())
        # Standing still with the person still inside the walking zone: the collision found while
        # walking is held (~hold_when_stopped) as long as they stay, though the rest zone is clear.
        self.assertTrue(all(s.collision for s in self.state_of_next("near", 20)))
        # They step away: released; back at 0.8 m while the robot stands: clear (the rest zone).
        self.settle("clear", False)
        self.settle("near", False)
        # Without the hold, the rest zone releases the walking collision at once (stop-and-go).
        client = dynamic_reconfigure.client.Client("/rbd_lidar", timeout=10)
        client.update_configuration({"hold_when_stopped": False})
        type(self).cmd = Twist()
        self.cmd.linear.x = 0.3
        self.settle("near", True)
        type(self).cmd = None
        self.cmd_pub.publish(Twist())
        self.settle("near", False)
        client.update_configuration({"hold_when_stopped": True})

        # dynamic_reconfigure: a 0.9 m front zone catches it at rest; back to 0.7 m clears it.
        client.update_configuration({"zone_front": 0.9})
        self.settle("near", True)
        client.update_configuration({"zone_front": 0.7})
        self.settle("near", False)

        # Tilted body (attentive sitting): without attitude the rear floor looks like an obstacle;
        # with the body pitch from odom the floor is rejected.
        self.settle("tilted", True)
        st = self.state_of_next("tilted")[0]
        self.assertGreater(st.points[CollisionState.BACK], 5)
        odom = Odometry()
        odom.header.frame_id = "odom"
        o = odom.pose.pose.orientation
        o.x, o.y, o.z, o.w = rpy_to_quat(0.0, self.pitch, 0.0)
        type(self).odom = odom
        self.settle("tilted", False)
        type(self).odom = None

        # Absent collision service: states keep coming; the pending change is delivered once the
        # service is back.
        self.wait_for(lambda: self.calls and self.calls[-1][1] is False, 5.0, "data=false call before")
        self.service.shutdown("test: service absent")
        master = rosgraph.Master(rospy.get_name())

        def gone():
            try:
                master.lookupService("/rbd_controller/collision")
            except rosgraph.MasterError:
                return True
            return False

        rbd_testkit.wait_for(gone, 5.0, what="the collision service gone from the master")
        with self.lock:
            n_calls = len(self.calls)
        self.settle("person", True)
        with self.lock:
            self.assertEqual(len(self.calls), n_calls)
        type(self).service = rospy.Service("/rbd_controller/collision", SetBool, self.on_call)
        self.wait_for(lambda: [d for _, d in self.calls[n_calls:]] == [True], 5.0, "pending call delivered")


if __name__ == "__main__":
    run_rostest("rbd_lidar", "synthetic_lidar", SyntheticLidarTest)
