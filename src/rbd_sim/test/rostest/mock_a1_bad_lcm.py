#!/usr/bin/env python3
"""rostest node: be the mock A1's LCM peer; malformed HighCmd packets must leave it standing still.

Measured on /rbd_sim/ground_truth. A valid command afterwards must move it (so the test can fail),
and when the commands stop, the A1's own watchdog must stop it. The malformed packets are proven
to have arrived by the mock's own count of rejected commands (its log on /rosout).
"""

import math
import random
import re
import threading
import time
import unittest

import lcm
import rospy
from nav_msgs.msg import Odometry

from rbd_testkit import stays_unchanged, wait_for, wait_quiet
from rbd_testkit.ros import RosoutWatcher, run_rostest
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
        cls.gt_count = 0  # ground-truth messages so far: the simulation goes on
        cls.states = []
        cls.lock = threading.Lock()
        rospy.Subscriber("/rbd_sim/ground_truth", Odometry, cls._gt, queue_size=5)
        cls.lc = lcm.LCM(rospy.get_param("~lcm_url"))
        cls.lc.subscribe(HIGH_STATE, cls._state)
        cls.running = True
        cls.rx = threading.Thread(target=cls._rx)
        cls.rx.daemon = True
        cls.rx.start()
        cls.rosout = RosoutWatcher()
        cls.rosout.wait_connected("/mock_a1", 60.0)
        wait_for(lambda: cls.pose is not None and cls.states, 60.0)

    def setUp(self):
        """Known state, whatever ran before: the mock stands still."""
        self.assertIsNotNone(self.get(), "no ground truth")
        self.wait_still("the mock standing still")

    def wait_still(self, what):
        """Wait until fresh ground truth moved less than 0.1 mm / 0.1 mrad over 0.2 s."""
        n = self.gt_count
        wait_quiet(self.get, 0.2, 5.0, 0.01, what=what, same=lambda a, b: all(v < 1e-4 for v in self.moved(a, b)))
        self.assertGreaterEqual(self.gt_count, n + 2, "the ground truth stopped coming: it only looked still")

    def rejected_so_far(self):
        """The mock's count of rejected HighCmd packets, from its latest (throttled) log line."""
        counts = [int(m.group(1)) for m in (re.search(r"rejected \((\d+) so far", line)
                                            for line in self.rosout.find("HighCmd rejected", node="/mock_a1")) if m]
        return max(counts) if counts else 0

    @classmethod
    def tearDownClass(cls):
        cls.running = False

    @classmethod
    def _gt(cls, msg):
        p = msg.pose.pose.position
        q = msg.pose.pose.orientation
        with cls.lock:
            cls.pose = (p.x, p.y, 2 * math.atan2(q.z, q.w))
            cls.gt_count += 1

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
        pace = rospy.Rate(1.0 / PERIOD)
        while time.monotonic() - t0 < duration:
            self.lc.publish(HIGH_CMD, packets[i % len(packets)])
            i += 1
            pace.sleep()

    def moved(self, a, b):
        return math.hypot(a[0] - b[0], a[1] - b[1]), abs(a[2] - b[2])

    def test_high_state_has_the_layouts_size(self):
        layout = rospy.get_param("~sdk_layout", "3.3.4")
        self.assertTrue(self.states, "no LCM_High_State received")
        with self.lock:
            self.assertEqual(set(self.states), {vendor.HIGH_STATES[layout].size})

    def test_malformed_packets_hold_still(self):
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
        n0 = self.rejected_so_far()
        stays_unchanged(
            lambda: [m >= 0.002 for m in self.moved(self.get(), start)],
            lambda: self.rejected_so_far() >= n0 + len(bad),
            0.3,
            send=lambda: self.send(bad, 2.0),
            what="moved (position, yaw) by 2 mm / 2 mrad",
            proof="the mock rejecting the packets (its count on /rosout)",
        )

    def test_valid_packets_move_and_watchdog_stops(self):
        nan = float("nan")
        start = self.get()
        # Valid commands interleaved with garbage: the garbage is ignored, the robot walks.
        self.send([walk(0.3), walk(nan), b"\x01\x02", walk(0.3, mode=200)], 1.5)
        at_last = self.get()
        d, _ = self.moved(at_last, start)
        self.assertGreater(d, 0.2, "valid commands did not move the mock (%.3f m)" % d)
        # the watchdog stops it: measured once the ground truth stands still (however long that takes)
        self.wait_still("the mock stopping after the last command")
        stopped = self.get()
        coast, _ = self.moved(stopped, at_last)
        # latency 0.05 s + watchdog 0.1 s at 0.3 m/s + 0.03 m braking = 0.075 m
        self.assertLess(coast, 0.16, "watchdog: coasted %.3f m" % coast)
        n = self.gt_count
        stays_unchanged(lambda: self.moved(self.get(), stopped)[0] < 0.002, lambda: self.gt_count >= n + 5, hold=0.5,
                        what="standing within 2 mm", proof="five new ground-truth messages")


if __name__ == "__main__":
    run_rostest(PKG, "mock_a1_bad_lcm", MockA1BadLcm)
