#!/usr/bin/env python3
"""rostest node: a fake A1 LCM server around the real rbd_a1_driver; checks the HighCmd bytes on the wire.

The test publishes HighState (so the driver sees a live robot) and records every HighCmd.
"""

import math
import threading
import time
import unittest

import lcm
import rospy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu
from std_msgs.msg import Bool

from rbd_a1_driver import unitree_layout as ul
from rbd_msgs.srv import SetBodyPose
from rbd_testkit import wait_for
from rbd_testkit.ros import run_rostest

PKG = "rbd_a1_driver"


def twist(vx=0.0, vy=0.0, wz=0.0):
    t = Twist()
    t.linear.x, t.linear.y, t.angular.z = vx, vy, wz
    return t


class DriverWire(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("driver_wire")
        cls.lock = threading.Lock()
        cls.cmds = []  # (monotonic time, HighCmd)
        cls.bad = []
        cls.state = ul.HighState()
        cls.state_on = True
        cls.running = True
        cls.estop_value = None  # last e-stop flag sent
        cls.estop_periodic = False  # a periodic e-stop source (10 Hz, like rbd_controller) is running
        cls.estop_last = 0.0  # monotonic time of the last e-stop message
        cls.lc = lcm.LCM(rospy.get_param("~lcm_url"))
        cls.lc.subscribe(ul.CHANNEL_HIGH_CMD, cls._on_cmd)
        for target in (cls._rx, cls._tx, cls._estop_source):
            th = threading.Thread(target=target)
            th.daemon = True
            th.start()
        cls.pub = rospy.Publisher("/cmd_vel", Twist, queue_size=5)
        cls.estop = rospy.Publisher("/rbd_controller/estop", Bool, queue_size=1, latch=True)
        cls.diag = []
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.diag.append)
        rospy.wait_for_message("/rbd_a1_driver/odom", Odometry, timeout=60.0)
        wait_for(lambda: cls.pub.get_num_connections() > 0, 30.0)

    def setUp(self):
        """Known state, whatever ran before: default fresh HighState, e-stop released, the driver walking."""
        with self.lock:
            DriverWire.state = ul.HighState()
        DriverWire.state_on = True
        if self.estop_value is not False:
            self.set_estop(False)  # only when needed: two one-shot messages < 0.5 s apart would arm the watchdog
        wait_for(lambda: self.send(twist(0.3), 0.1) and abs(self.last().velocity[0] - 0.3) < 1e-5, 5.0,
                 what="the driver walking on cmd_vel")

    @classmethod
    def set_estop(cls, value):
        """Send one e-stop message (and make it the value a running periodic source repeats)."""
        cls.estop_value = value
        cls.estop_last = time.monotonic()
        cls.estop.publish(Bool(value))

    @classmethod
    def _estop_source(cls):
        while cls.running:
            if cls.estop_periodic and cls.estop_value is not None:
                cls.set_estop(cls.estop_value)
            time.sleep(0.1)

    @classmethod
    def tearDownClass(cls):
        cls.running = False

    @classmethod
    def _on_cmd(cls, channel, data):
        try:
            cmd = ul.decode_high_cmd(data)
        except ul.LayoutError as e:
            cls.bad.append(str(e))
            return
        with cls.lock:
            cls.cmds.append((time.monotonic(), cmd))
            del cls.cmds[:-2000]

    @classmethod
    def _rx(cls):
        while cls.running:
            cls.lc.handle_timeout(100)

    @classmethod
    def _tx(cls):
        while cls.running:
            if cls.state_on:
                with cls.lock:
                    data = cls.state.pack()
                cls.lc.publish(ul.CHANNEL_HIGH_STATE, data)
            time.sleep(0.005)

    def last(self):
        with self.lock:
            return self.cmds[-1][1]

    def since(self, t0):
        with self.lock:
            return [(t, c) for t, c in self.cmds if t >= t0]

    def send(self, msg, duration, rate=20.0):
        t0 = t_pub = time.monotonic()
        while time.monotonic() - t0 < duration:
            t_pub = time.monotonic()
            self.pub.publish(msg)
            time.sleep(1.0 / rate)
        return t_pub

    def test_every_packet_is_a_valid_v33_high_cmd(self):
        time.sleep(0.5)
        self.assertEqual(self.bad, [])
        with self.lock:
            self.assertGreater(len(self.cmds), 20)

    def test_cmd_vel_to_velocity_walk(self):
        self.send(twist(0.3, 0.1, 0.2), 0.5)
        c = self.last()
        self.assertEqual((c.mode, c.gait_type), (ul.MODE_VELOCITY_WALK, ul.GAIT_TROT))
        self.assertAlmostEqual(c.velocity[0], 0.3, places=5)
        self.assertAlmostEqual(c.velocity[1], 0.1, places=5)
        self.assertAlmostEqual(c.yaw_speed, 0.2, places=5)

    def test_clamped(self):
        self.send(twist(5.0, -5.0, 9.0), 0.5)
        c = self.last()
        self.assertAlmostEqual(c.velocity[0], 0.5, places=5)
        self.assertAlmostEqual(c.velocity[1], -0.3, places=5)
        self.assertAlmostEqual(c.yaw_speed, 1.0, places=5)

    def test_zero_after_025s_without_cmd_vel(self):
        t_last = self.send(twist(0.3), 0.5)
        time.sleep(0.8)
        cmds = self.since(t_last)
        first_zero = next(t for t, c in cmds if c.velocity == (0.0, 0.0) and c.yaw_speed == 0.0)
        delay = first_zero - t_last
        rospy.loginfo("MEASURED zero velocity %.3f s after the last cmd_vel", delay)
        self.assertGreater(delay, 0.2)
        self.assertLess(delay, 0.45)
        self.assertTrue(all(c.velocity == (0.0, 0.0) for t, c in cmds if t > first_zero))

    def test_nan_gives_zero(self):
        self.send(twist(0.3), 0.3)
        t0 = time.monotonic()
        self.send(twist(float("nan")), 0.3)
        late = [c for t, c in self.since(t0 + 0.1)]
        self.assertTrue(late)
        self.assertTrue(all(c.velocity == (0.0, 0.0) for c in late))

    def test_estop(self):
        released = False
        try:
            self.send(twist(0.3), 0.3)
            self.set_estop(True)
            t0 = time.monotonic()
            self.send(twist(0.3), 0.5)
            late = [c for t, c in self.since(t0 + 0.1)]
            self.assertTrue(all(c.velocity == (0.0, 0.0) for c in late))
            time.sleep(0.3)  # one-shot messages > estop_timeout apart: the signal watchdog stays unarmed
            self.set_estop(False)
            released = True
            self.send(twist(0.3), 0.3)
            self.assertAlmostEqual(self.last().velocity[0], 0.3, places=5)
        finally:
            if not released:
                self.set_estop(False)

    def test_stale_high_state_gives_zero_and_error(self):
        try:
            self.send(twist(0.3), 0.3)
            DriverWire.state_on = False
            t0 = time.monotonic()
            self.send(twist(0.3), 1.5)
            late = [c for t, c in self.since(t0 + 0.7)]
            self.assertTrue(late, "the driver must keep sending while the state is stale")
            self.assertTrue(all(c.velocity == (0.0, 0.0) for c in late))
            deadline = time.monotonic() + 3.0
            while time.monotonic() < deadline and not any(
                s.level == DiagnosticStatus.ERROR for s in self.diag[-1].status
            ):
                self.pub.publish(twist(0.3))
                time.sleep(0.05)
            self.assertEqual(self.diag[-1].status[0].level, DiagnosticStatus.ERROR,
                             "no diagnostics ERROR while HighState is stale")
        finally:
            DriverWire.state_on = True
        self.send(twist(0.3), 0.3)
        self.assertAlmostEqual(self.last().velocity[0], 0.3, places=5)

    def test_body_pose_force_stand(self):
        call = rospy.ServiceProxy("/set_body_pose", SetBodyPose)
        rospy.wait_for_service("/set_body_pose", timeout=10.0)
        self.assertTrue(call(0.2, -0.3, 0.1, -0.1).success)
        self.assertFalse(call(float("nan"), 0.0, 0.0, 0.0).success)
        self.assertFalse(call(2.0, 0.0, 0.0, 0.0).success)
        time.sleep(0.8)  # stand_delay after the last motion
        c = self.last()
        self.assertEqual(c.mode, ul.MODE_FORCE_STAND)
        for got, want in zip(c.euler + (c.body_height,), (0.2, -0.3, 0.1, -0.1)):
            self.assertAlmostEqual(got, want, places=5)
        self.assertTrue(call(0.0, 0.0, 0.0, 0.0).success)

    def test_odom_and_imu_from_high_state(self):
        s = ul.HighState()
        s.position = (1.5, -0.5, 0.0)
        s.quaternion = (math.cos(0.25), 0.0, 0.0, math.sin(0.25))  # yaw 0.5 rad
        s.velocity = (0.2, 0.05, 0.0)
        s.gyroscope = (0.0, 0.0, 0.3)
        s.accelerometer = (0.1, 0.0, 9.8)
        with self.lock:
            DriverWire.state = s
        time.sleep(0.3)
        odom = rospy.wait_for_message("/rbd_a1_driver/odom", Odometry, timeout=5.0)
        imu = rospy.wait_for_message("/rbd_a1_driver/imu", Imu, timeout=5.0)
        self.assertEqual((odom.header.frame_id, odom.child_frame_id), ("odom", "base_link"))
        p, q = odom.pose.pose.position, odom.pose.pose.orientation
        self.assertAlmostEqual(p.x, 1.5, places=5)
        self.assertAlmostEqual(p.y, -0.5, places=5)
        self.assertAlmostEqual(2 * math.atan2(q.z, q.w), 0.5, places=5)
        self.assertAlmostEqual(odom.twist.twist.linear.x, 0.2, places=5)
        self.assertAlmostEqual(odom.twist.twist.angular.z, 0.3, places=5)
        self.assertEqual(imu.header.frame_id, "base_link")
        self.assertAlmostEqual(imu.angular_velocity.z, 0.3, places=5)
        self.assertAlmostEqual(imu.linear_acceleration.z, 9.8, places=5)
        self.assertAlmostEqual(imu.orientation.z, math.sin(0.25), places=5)

    def test_estop_signal_lost_engages_until_fresh_false(self):
        """A periodic e-stop source that goes silent (controller killed) engages the gate.

        The watchdog stays armed for the rest of the run: the periodic source is left running for
        the tests that follow (as rbd_controller runs beside the driver).
        """
        try:
            DriverWire.estop_value = False
            DriverWire.estop_periodic = True
            self.send(twist(0.3), 1.5)  # periodic false (armed) while walking
            self.assertAlmostEqual(self.last().velocity[0], 0.3, places=5, msg="not walking while armed")
            DriverWire.estop_periodic = False
            time.sleep(0.15)  # the source thread's last message
            t_last = self.estop_last
            self.send(twist(0.3), 1.5)  # e-stop messages stop; cmd_vel keeps coming
            late = [c for t, c in self.since(t_last + 0.5 + 0.3)]
            self.assertTrue(late)
            self.assertTrue(all(c.velocity == (0.0, 0.0) for c in late), "still walking without e-stop signal")
            moving = [t for t, c in self.since(t_last) if c.velocity != (0.0, 0.0)]
            self.assertTrue(moving and moving[-1] - t_last > 0.3, "engaged before the timeout")
            deadline = time.monotonic() + 2.5
            while time.monotonic() < deadline and not any(
                s.level == DiagnosticStatus.ERROR and "e-stop" in s.message for s in self.diag[-1].status
            ):
                self.pub.publish(twist(0.3))
                time.sleep(0.05)
            self.assertIn("e-stop signal lost", self.diag[-1].status[0].message)
            self.assertEqual(self.last().velocity, (0.0, 0.0))
            self.set_estop(False)  # a fresh false releases
            self.send(twist(0.3), 0.3)
            self.assertAlmostEqual(self.last().velocity[0], 0.3, places=5, msg="no motion after a fresh false")
        finally:
            DriverWire.estop_value = False
            DriverWire.estop_periodic = True


if __name__ == "__main__":
    run_rostest(PKG, "driver_wire", DriverWire)
