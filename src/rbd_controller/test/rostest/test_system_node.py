#!/usr/bin/env python3
"""rostest: the control nodes together on rbd_sim's mock A1 + rbd_a1_driver, measured on ground truth."""

import math
import subprocess
import threading
import time
import unittest

import rospy
from geometry_msgs.msg import PoseStamped, Vector3
from nav_msgs.msg import Odometry, Path
from std_msgs.msg import Bool, String
from std_srvs.srv import SetBool

from rbd_geometry.rotation import quat_to_rpy, yaw_of
from rbd_msgs.msg import ControllerState, PathQueue
from rbd_testkit import stays_unchanged, wait_for
from rbd_testkit.ros import RosoutWatcher, run_rostest

CONTROL_PERIOD = 1.0 / 20.0  # rbd_pos_controller rate
MARGIN = 0.25  # scheduling margin for a loaded machine [s]
STILL = 1e-3  # |velocity| below this counts as standing still [m/s, rad/s]
GESTURE_TOPIC = "/rbd_gestrec/gesture"
WRONG_TOPIC = "/rbd_gestrec/gesture_typo"  # for the companion test of the negative checks
HOLD = 1.0  # a gesture ignored: nothing may happen for this long after it was proven to arrive [s]


class World:
    def __init__(self):
        self.lock = threading.Lock()
        self.truth = None
        self.applied = []  # (t, vx, vy, wz) actually acting on the robot
        self.state = ""
        self.states = []
        self.pos_state = ""
        self.estop = None
        self.queue = None
        self.path = None
        self.cstate = None
        self.body = None
        rospy.Subscriber("/rbd_sim/ground_truth_pose", PoseStamped, self.on_truth)
        # ~stop_time allows for the mock A1's deceleration limits when judging "stopped in time".
        self.stop_time = float(rospy.get_param("~stop_time", 0.4))
        rospy.Subscriber("/rbd_sim/ground_truth", Odometry, self.on_odometry)
        rospy.Subscriber("/rbd_controller/state", String, self.on_state)
        rospy.Subscriber("/rbd_pos_controller/state", String, self.on_pos_state)
        rospy.Subscriber("/rbd_controller/estop", Bool, lambda m: setattr(self, "estop", m.data))
        rospy.Subscriber("/rbd_controller/path_queue", PathQueue, lambda m: setattr(self, "queue", m))
        rospy.Subscriber("/rbd_controller/path", Path, lambda m: setattr(self, "path", m))
        rospy.Subscriber("/rbd_controller/controller_state", ControllerState, lambda m: setattr(self, "cstate", m))

    def on_truth(self, msg):
        with self.lock:
            self.truth = msg.pose

    def on_velocity(self, msg):
        with self.lock:
            self.applied.append((time.monotonic(), msg.linear.x, msg.linear.y, msg.angular.z))

    def on_odometry(self, msg):
        pitch = quat_to_rpy(msg.pose.pose.orientation)[1]
        self.body = Vector3(0.0, pitch, 0.0)
        self.on_velocity(msg.twist.twist)

    def on_state(self, msg):
        with self.lock:
            self.state = msg.data
            self.states.append(msg.data)

    def on_pos_state(self, msg):
        self.pos_state = msg.data

    def pose(self):
        with self.lock:
            p = self.truth
        return p.position.x, p.position.y, yaw_of(p.orientation)

    def moving_since(self, t0):
        with self.lock:
            return [v for v in self.applied if v[0] >= t0 and any(abs(c) > STILL for c in v[1:])]

    def last_sample(self):
        """Receipt time of the newest ground-truth velocity sample (0.0 before the first)."""
        with self.lock:
            return self.applied[-1][0] if self.applied else 0.0

    def first_zero_after(self, t0):
        with self.lock:
            for v in self.applied:
                if v[0] >= t0 and all(abs(c) <= STILL for c in v[1:]):
                    return v[0] - t0
        return None


class TestControlSystem(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_control_system", anonymous=True)
        cls.w = World()
        for name in (
            "/rbd_controller/em_stop",
            "/rbd_controller/collision",
            "/rbd_pos_controller/set_position",
            "/rbd_navigation/generate_path",
            "/rbd_gestrec/get_last_gesture",
        ):
            rospy.wait_for_service(name, timeout=60.0)
        cls.em_stop = rospy.ServiceProxy("/rbd_controller/em_stop", SetBool)
        cls.collision = rospy.ServiceProxy("/rbd_controller/collision", SetBool)
        cls.publishers = {}
        cls.gesture = cls.publisher(GESTURE_TOPIC)
        cls.rosout = RosoutWatcher()
        for node in ("/rbd_gestrec", "/rbd_controller"):
            cls.rosout.wait_connected(node, 30.0)
        assert wait_for(lambda: cls.w.truth is not None and cls.w.state and cls.w.estop is not None
                        and cls.gesture.get_num_connections() > 0, 30.0)
        # The first (latched) state and e-stop flag, before any test released anything.
        cls.power_up = (cls.w.states[0], cls.w.estop)

    @classmethod
    def publisher(cls, topic):
        if topic not in cls.publishers:
            cls.publishers[topic] = rospy.Publisher(topic, String, queue_size=10)
        return cls.publishers[topic]

    # -------------------------------------------------------------- helpers
    def send_gesture(self, label, topic=GESTURE_TOPIC):
        self.publisher(topic).publish(String(label))

    def ready_waiting(self):
        """Known state, whatever ran before: no stop, no trick, WAITING_FOR_GESTURE."""
        self.em_stop(data=False)
        self.collision(data=False)
        self.wait_state("WAITING_FOR_GESTURE", 40.0)

    def start_trick(self, label, timeout=60.0):
        """Show a gesture until the controller takes it as its command.

        The controller's first gesture poll after it became ready drops what it finds (a gesture
        made while it was busy or stopped). A gesture that meets that poll is shown again, as a
        visitor would; the controller's own log line says which of the two happened.
        """
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.assertEqual(self.w.state, "WAITING_FOR_GESTURE")
            mark = self.rosout.mark()
            self.send_gesture(label)

            def answer(since=mark):
                taken = self.rosout.find("gesture command %r" % label, node="/rbd_controller", since=since)
                return taken or self.rosout.find("dropping gesture %r" % label, node="/rbd_controller", since=since)

            lines = wait_for(answer, min(10.0, max(0.0, deadline - time.monotonic())), 0.02)
            if lines and "gesture command" in lines[0]:
                return
        self.fail("the controller never took gesture %r as a command" % label)

    def engage_estop(self):
        self.em_stop(data=True)
        self.wait_state("EMERGENCY_STOP", 30.0)
        self.assertTrue(wait_for(lambda: self.w.estop is True, 30.0), "latched /rbd_controller/estop")

    def check_gesture_ignored_in_estop(self, topic=GESTURE_TOPIC, proof_timeout=10.0):
        """In EMERGENCY_STOP, a gesture that reached rbd_gestrec changes nothing; released, it is dropped.

        Proof that the gesture arrived: rbd_gestrec's own log line for it, then (after the release)
        the controller's "dropping gesture" line. Published to a wrong topic, neither comes and this
        check fails (test_negative_checks_fail_on_a_wrong_topic).
        """
        self.assertEqual(self.w.state, "EMERGENCY_STOP")
        t0 = time.monotonic()
        mark = self.rosout.mark()
        stays_unchanged(
            lambda: (self.w.state, self.w.moving_since(t0)),
            lambda: self.rosout.find("gesture 'spin' -> command", node="/rbd_gestrec", since=mark),
            HOLD,
            send=lambda: self.send_gesture("spin", topic),
            timeout=proof_timeout,
            what="controller state and motion at the robot",
            proof="rbd_gestrec taking the gesture",
        )
        n = len(self.w.states)
        stays_unchanged(
            lambda: (self.w.moving_since(t0), [s for s in self.w.states[n:] if s != "WAITING_FOR_GESTURE"]),
            lambda: self.rosout.find("dropping gesture 'spin'", node="/rbd_controller", since=mark),
            0.6,
            send=lambda: self.em_stop(data=False),
            timeout=proof_timeout,
            what="motion and states after the release",
            proof="the controller dropping the gesture made during the e-stop",
        )
        self.assertEqual(self.w.state, "WAITING_FOR_GESTURE")

    def check_unknown_gesture_ignored(self, topic=GESTURE_TOPIC, proof_timeout=10.0):
        """An unknown gesture that reached rbd_gestrec moves nothing and leaves the state as it was.

        Proof that it arrived: rbd_gestrec's warning about it (throttled to one per 2 s: this is the
        only unknown gesture this test sends). Published to a wrong topic, the proof never comes and
        this check fails (test_negative_checks_fail_on_a_wrong_topic).
        """
        self.ready_waiting()
        t0 = time.monotonic()
        mark = self.rosout.mark()
        stays_unchanged(
            lambda: (self.w.state, self.w.moving_since(t0)),
            lambda: self.rosout.find("unknown gesture 'backflip'", node="/rbd_gestrec", since=mark),
            HOLD,
            send=lambda: self.send_gesture("backflip", topic),
            timeout=proof_timeout,
            what="controller state and motion at the robot",
            proof="rbd_gestrec rejecting the gesture",
        )

    def wait_state(self, name, timeout=10.0):
        self.assertTrue(wait_for(lambda: self.w.state == name, timeout), "state %r, wanted %s" % (self.w.state, name))

    def wait_pos_state(self, name, timeout=20.0):
        self.assertTrue(
            wait_for(lambda: self.w.pos_state == name, timeout), "pos state %r, wanted %s" % (self.w.pos_state, name)
        )

    def wait_moving_in(self, pos_state):
        """Wait for pos_state and for the robot to actually move in it."""
        self.wait_pos_state(pos_state)
        self.assertTrue(wait_for(lambda: self.w.moving_since(time.monotonic() - 0.05), 30.0), pos_state)
        self.assertEqual(self.w.pos_state, pos_state)

    def assert_stops(self, t0, label):
        """Zero velocity reaches the robot promptly and the robot stays still."""
        self.assertTrue(wait_for(lambda: self.w.first_zero_after(t0) is not None, 30.0), label)
        delay = self.w.first_zero_after(t0)
        rospy.loginfo("%s: zero velocity at the robot %.3f s after the request", label, delay)
        self.assertLess(delay, CONTROL_PERIOD + MARGIN + self.w.stop_time, label)
        # the check starts 0.3 s after the first zero (deceleration), at a ground-truth sample
        settled = t0 + delay + 0.3
        self.assertTrue(wait_for(lambda: self.w.last_sample() >= settled, 5.0), "%s: ground truth stopped" % label)
        self.assert_still(0.5, label)

    def assert_still(self, hold, label):
        """No motion at the robot for ``hold`` s, proven on fresh ground truth (a stale simulator fails)."""
        t1 = time.monotonic()
        x0, y0, yaw0 = self.w.pose()

        def still():
            x1, y1, yaw1 = self.w.pose()
            return not self.w.moving_since(t1) and math.hypot(x1 - x0, y1 - y0) + abs(yaw1 - yaw0) < 1e-3

        stays_unchanged(still, lambda: self.w.last_sample() > t1, hold, timeout=5.0,
                        what="%s: the robot at rest" % label, proof="a fresh ground-truth sample")
        self.assertGreater(self.w.last_sample(), t1 + hold - 0.2, "%s: ground truth stopped coming" % label)

    def assert_back_at_start(self, start):
        x, y, yaw = self.w.pose()
        self.assertLess(math.hypot(x - start[0], y - start[1]), 0.05)
        self.assertLess(abs(math.atan2(math.sin(yaw - start[2]), math.cos(yaw - start[2]))), math.radians(3.0))

    # -------------------------------------------------------------- tests (any order: each sets up its state)
    def test_power_up_in_estop(self):
        self.assertEqual(self.power_up, ("EMERGENCY_STOP", True))

    def test_gesture_during_estop_is_ignored_then_dropped(self):
        self.engage_estop()  # already engaged when this test runs first (power-up)
        self.check_gesture_ignored_in_estop()

    def test_cli_release_then_gesture_runs_trick(self):
        self.engage_estop()
        out = subprocess.run(
            ["rosrun", "rbd_controller", "estop", "off"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=30
        )
        self.assertEqual(out.returncode, 0, out.stdout)
        self.wait_state("WAITING_FOR_GESTURE")
        self.assertTrue(wait_for(lambda: self.w.estop is False, 30.0))
        self.assertTrue(wait_for(lambda: self.w.body is not None and self.w.body.y < -0.1, 5.0), "attentive pitch")
        start = self.w.pose()
        n = len(self.w.states)
        # only this trick's queue, path and controller state count (not an earlier test's last ones)
        self.w.queue = self.w.path = self.w.cstate = None
        self.start_trick("walk")
        self.wait_state("EXECUTING", 30.0)
        self.assertTrue(wait_for(lambda: self.w.queue is not None and len(self.w.queue.names) == 2, 30.0))
        self.assertEqual(self.w.queue.command, "walk")
        self.assertEqual(self.w.queue.names[0], "out 0.45 m, turn left")
        self.assertTrue(
            wait_for(lambda: self.w.path is not None and len(self.w.path.poses) == 2, 30.0), "nav_msgs/Path"
        )
        # its own latched topic (published with the state): it may arrive after /state and /path_queue
        self.assertTrue(wait_for(lambda: self.w.cstate is not None and self.w.cstate.state_name == "EXECUTING", 30.0),
                        "controller_state: %s" % (self.w.cstate and self.w.cstate.state_name))
        self.assertTrue(wait_for(lambda: abs(self.w.body.y) < 0.02, 30.0), "neutral body before moving")
        self.wait_state("WAITING_FOR_GESTURE", 40.0)
        self.assertEqual(self.w.states[n:], ["GENERATING_PATH", "EXECUTING", "WAITING_FOR_GESTURE"])
        self.assert_back_at_start(start)
        # the queue is its own topic: its empty message may arrive just after the state's
        self.assertTrue(wait_for(lambda: len(self.w.queue.names) == 0, 30.0), self.w.queue.names)

    def test_unknown_gesture_no_motion(self):
        self.check_unknown_gesture_ignored()

    def test_negative_checks_fail_on_a_wrong_topic(self):
        """The two negative checks above fail, not pass, when their gesture goes to a wrong topic."""
        with self.assertRaisesRegex(AssertionError, "no proof of rbd_gestrec rejecting the gesture"):
            self.check_unknown_gesture_ignored(WRONG_TOPIC, proof_timeout=2.0)
        self.engage_estop()
        with self.assertRaisesRegex(AssertionError, "no proof of rbd_gestrec taking the gesture"):
            self.check_gesture_ignored_in_estop(WRONG_TOPIC, proof_timeout=2.0)

    def test_estop_in_every_motion_state_then_resume(self):
        self.ready_waiting()
        start = self.w.pose()
        self.start_trick("walk")
        for pos_state in ("LINEAR", "POST_ROTATION", "PRE_ROTATION"):
            self.wait_moving_in(pos_state)
            self.assertEqual(self.w.state, "EXECUTING")
            t0 = time.monotonic()
            self.em_stop(data=True)
            self.assertTrue(wait_for(lambda: self.w.estop is True, 30.0), "latched /rbd_controller/estop")
            self.wait_state("EMERGENCY_STOP", 30.0)
            self.assert_stops(t0, "e-stop in " + pos_state)
            self.em_stop(data=False)
            self.wait_state("EXECUTING", 30.0)
        self.wait_state("WAITING_FOR_GESTURE", 40.0)
        self.assert_back_at_start(start)

    def test_estop_while_waiting(self):
        self.ready_waiting()
        self.engage_estop()
        self.check_gesture_ignored_in_estop()

    def test_collision_stops_and_clear_resumes(self):
        self.ready_waiting()
        start = self.w.pose()
        self.start_trick("walk")
        self.wait_moving_in("LINEAR")
        t0 = time.monotonic()
        self.collision(data=True)
        self.wait_state("COLLISION_DETECTED", 30.0)
        self.assert_stops(t0, "collision in LINEAR")
        # an e-stop on top of the collision; releasing it keeps the collision stop
        self.em_stop(data=True)
        self.wait_state("EMERGENCY_STOP", 30.0)
        self.em_stop(data=False)
        self.wait_state("COLLISION_DETECTED", 30.0)
        self.assert_still(0.5, "e-stop released, collision held")
        self.collision(data=False)
        self.wait_state("EXECUTING", 30.0)
        self.wait_state("WAITING_FOR_GESTURE", 40.0)
        self.assert_back_at_start(start)


if __name__ == "__main__":
    run_rostest("rbd_controller", "control_system_wiring", TestControlSystem)
