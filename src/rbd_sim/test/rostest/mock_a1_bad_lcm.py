#!/usr/bin/env python3
"""rostest node: be the mock A1's LCM peer; malformed HighCmd packets must leave it standing still.

Measured on /rbd_sim/ground_truth. A valid command afterwards must move it (so the test can fail),
and when the commands stop, the A1's own watchdog must stop it.
"""

import math
import random
import threading
import time
import unittest

import lcm
import rospy
import rostest
from nav_msgs.msg import Odometry

from rbd_wire_oracle import unitree as vendor

PKG = "rbd_sim"
PERIOD = 0.004  # 250 Hz, like the driver
HIGH_CMD, HIGH_STATE = "LCM_High_Cmd", "LCM_High_State"


def walk(vx=0.0, wz=0.0, **fields):
    """A HighCmd assembled from the vendor's offsets; ``fields`` (SDK names) override."""
    values = {"mode": vendor.MODE_VELOCITY_WALK, "gaitType": vendor.GAIT_TROT, "velocity": (vx, 0.0),
              "yawSpeed": wz}
    values.update(fields)
    return vendor.pack(vendor.HIGH_CMD, values)


class MockA1BadLcm(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("mock_a1_bad_lcm")
        cls.pose = None
        cls.states = []
        cls.lock = threading.Lock()
        rospy.Subscriber("/rbd_sim/ground_truth", Odometry, cls._gt, queue_size=5)
        cls.lc = lcm.LCM(rospy.get_param("~lcm_url"))
        cls.lc.subscribe(HIGH_STATE, cls._state)
        cls.running = True
        cls.rx = threading.Thread(target=cls._rx)
        cls.rx.daemon = True
        cls.rx.start()
        deadline = time.monotonic() + 60.0
        while (cls.pose is None or not cls.states) and time.monotonic() < deadline:
            time.sleep(0.05)

    @classmethod
    def tearDownClass(cls):
        cls.running = False

    @classmethod
    def _gt(cls, msg):
        p = msg.pose.pose.position
        q = msg.pose.pose.orientation
        with cls.lock:
            cls.pose = (p.x, p.y, 2 * math.atan2(q.z, q.w))

    @classmethod
    def _state(cls, channel, data):
        with cls.lock:
            cls.states.append(len(data))
            del cls.states[:-100]

    @classmethod
    def _rx(cls):
        while cls.running:
            cls.lc.handle_timeout(100)

    def get(self):
        with self.lock:
            return self.pose

    def send(self, packets, duration):
        t0 = time.monotonic()
        i = 0
        while time.monotonic() - t0 < duration:
            self.lc.publish(HIGH_CMD, packets[i % len(packets)])
            i += 1
            time.sleep(PERIOD)

    def moved(self, a, b):
        return math.hypot(a[0] - b[0], a[1] - b[1]), abs(a[2] - b[2])

    def test_1_high_state_has_the_layouts_size(self):
        layout = rospy.get_param("~sdk_layout", "3.3.4")
        self.assertTrue(self.states, "no LCM_High_State received")
        with self.lock:
            self.assertEqual(set(self.states), {vendor.HIGH_STATES[layout].size})

    def test_2_malformed_packets_hold_still(self):
        rng = random.Random(11)
        nan, inf = float("nan"), float("inf")
        bad = [
            b"",
            b"\x00" * 112,
            walk(0.5) + b"\x00",
            walk(0.5)[:-20],
            b"\x00" * 143,  # an SDK v3.2 HighCmd
            walk(nan),
            walk(0.5, wz=inf),
            walk(0.5, mode=42),
            walk(0.5, gaitType=9),
            walk(0.5, levelFlag=0xEE),
        ]
        bad += [bytes(rng.getrandbits(8) for _ in range(vendor.HIGH_CMD.size)) for _ in range(40)]
        bad += [bytes(rng.getrandbits(8) for _ in range(rng.randint(1, 300))) for _ in range(20)]
        start = self.get()
        self.send(bad, 2.0)
        time.sleep(0.3)
        d, dyaw = self.moved(self.get(), start)
        self.assertLess(d, 0.002, "moved %.4f m on malformed packets" % d)
        self.assertLess(dyaw, 0.002)

    def test_3_valid_packets_move_and_watchdog_stops(self):
        nan = float("nan")
        start = self.get()
        # Valid commands interleaved with garbage: the garbage is ignored, the robot walks.
        self.send([walk(0.3), walk(nan), b"\x01\x02", walk(0.3, mode=200)], 1.5)
        at_last = self.get()
        d, _ = self.moved(at_last, start)
        self.assertGreater(d, 0.2, "valid commands did not move the mock (%.3f m)" % d)
        time.sleep(1.0)
        stopped = self.get()
        coast, _ = self.moved(stopped, at_last)
        # latency 0.05 s + watchdog 0.1 s at 0.3 m/s + 0.03 m braking = 0.075 m
        self.assertLess(coast, 0.16, "watchdog: coasted %.3f m" % coast)
        time.sleep(0.5)
        d, _ = self.moved(self.get(), stopped)
        self.assertLess(d, 0.002)


if __name__ == "__main__":
    rostest.rosrun(PKG, "mock_a1_bad_lcm", MockA1BadLcm)
