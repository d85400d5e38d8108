#!/usr/bin/env python3
"""rostest fault "ZED2 jumping 1 m" (issue 10, DESIGN §5): the controllers follow the localization.

The EKF reads the ZED2 pose through this test's relay (``zed2_pose:=/reliability/zed2_pose``).
While the robot walks the ``walk`` trick, the relay shifts the ZED2 pose by ``~jump`` metres
sideways (a lasting shift, like a real ZED relocalising into a wrong place) and removes it again
``~jump_duration`` seconds later. Measured on the simulator's ground truth:

- the robot does not lunge: its path stays within ``~max_path_deviation`` of the planned path
  (/rbd_controller/path) and its speed within ``~max_speed``;
- the jump is rejected: ``/rbd_localization/pose`` stays within ``~max_pose_error`` of ground
  truth the whole time, and the EKF reports rejected ZED2 samples on /diagnostics;
- the trick still completes and ends at its goal.

One ``FAULT_RESULT {json}`` line is printed (and appended to $RBD_FAULT_LOG if set).

It runs on sim_smoke.test's stack (that is this fault's system; one start-up instead of two):
``Zed2JumpFault`` is a mixin of test_sim_smoke.py's case, whose class set-up starts the relay
(``Zed2Relay``) before either test, so the EKF fuses the ZED2 whichever test runs first.
"""

import bisect
import math
import threading
import time

import rospy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped
from nav_msgs.msg import Odometry, Path
from std_msgs.msg import String
from std_srvs.srv import SetBool

import rbd_testkit
from rbd_bringup import a1_monitor


def shifted(msg, dx, dy):
    """Copy of a PoseWithCovarianceStamped moved by (dx, dy) metres in its frame."""
    out = PoseWithCovarianceStamped()
    out.header = msg.header
    out.pose.covariance = msg.pose.covariance
    out.pose.pose.orientation = msg.pose.pose.orientation
    out.pose.pose.position.x = msg.pose.pose.position.x + dx
    out.pose.pose.position.y = msg.pose.pose.position.y + dy
    out.pose.pose.position.z = msg.pose.pose.position.z
    return out


def distance_to_polyline(px, py, points):
    """Shortest distance [m] from (px, py) to the polyline through points [(x, y), ...]."""
    if len(points) == 1:
        return math.hypot(px - points[0][0], py - points[0][1])
    best = float("inf")
    for (ax, ay), (bx, by) in zip(points[:-1], points[1:]):
        dx, dy = bx - ax, by - ay
        n = dx * dx + dy * dy
        s = 0.0 if n < 1e-12 else max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / n))
        best = min(best, math.hypot(px - ax - s * dx, py - ay - s * dy))
    return best


class Zed2Relay:
    """The ZED2 relay (shifts by ``offset``) and what the fault measures, for the node's lifetime.

    One per node: a second relay would keep publishing the unshifted pose.
    """

    def __init__(self):
        self.lock = threading.Lock()
        self.offset = (0.0, 0.0)
        self.truth_t, self.truth = [], []  # stamp [s], (x, y, speed)
        self.pose_errors = []  # (stamp, |pose - truth|)
        self.pending = []  # (stamp, x, y) of poses newer than the last truth received
        self.path = []  # (x, y) of the planned path
        self.state = None
        self.rejected = 0
        self.pose0_reports = 0  # pose0 (ZED2) statuses of the EKF on /diagnostics so far
        self.relayed = 0
        self.zed_pub = rospy.Publisher("/reliability/zed2_pose", PoseWithCovarianceStamped, queue_size=10)
        self.gesture = rospy.Publisher("/rbd_gestrec/gesture", String, queue_size=10)
        rospy.Subscriber("/zed2/zed_node/pose_with_covariance", PoseWithCovarianceStamped, self.on_zed, queue_size=10)
        rospy.Subscriber("/rbd_sim/ground_truth", Odometry, self.on_truth, queue_size=100)
        rospy.Subscriber("/rbd_localization/pose", PoseStamped, self.on_pose, queue_size=50)
        rospy.Subscriber("/rbd_controller/path", Path, self.on_path, queue_size=5)
        rospy.Subscriber("/rbd_controller/state", String, self.on_state, queue_size=20)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=20)

    # ------------------------------------------------------------ callbacks
    def on_zed(self, msg):
        with self.lock:
            dx, dy = self.offset
        self.zed_pub.publish(shifted(msg, dx, dy))
        self.relayed += 1

    def on_truth(self, msg):
        p, v = msg.pose.pose.position, msg.twist.twist.linear
        with self.lock:
            self.truth_t.append(msg.header.stamp.to_sec())
            self.truth.append((p.x, p.y, math.hypot(v.x, v.y)))
            waiting, self.pending = self.pending, []
            for pose in waiting:
                self._match(*pose)

    def on_pose(self, msg):
        with self.lock:
            self._match(msg.header.stamp.to_sec(), msg.pose.position.x, msg.pose.position.y)

    def _match(self, t, x, y):
        """Record the pose's error against the truth nearest its stamp (lock held). A pose newer
        than the last truth received waits for the next truth (the EKF stamps "now"; the truth
        that brackets it may still be on its way)."""
        i = bisect.bisect_left(self.truth_t, t)
        if not self.truth_t or (i == 0 and self.truth_t[0] - t > 0.02):
            return
        if i >= len(self.truth_t):
            self.pending.append((t, x, y))
            return
        if i > 0 and t - self.truth_t[i - 1] < self.truth_t[i] - t:
            i -= 1
        tx, ty, _ = self.truth[i]
        self.pose_errors.append((t, math.hypot(x - tx, y - ty)))

    def on_path(self, msg):
        # The controller may publish the path goal by goal: keep every new point, in order.
        with self.lock:
            for p in msg.poses:
                pt = (p.pose.position.x, p.pose.position.y)
                if not self.path or math.hypot(pt[0] - self.path[-1][0], pt[1] - self.path[-1][1]) > 1e-3:
                    self.path.append(pt)

    def on_state(self, msg):
        self.state = msg.data

    def on_diagnostics(self, msg):
        for status in msg.status:
            if "pose0" in status.name:
                self.pose0_reports += 1
                for kv in status.values:
                    if kv.key == "rejected":
                        self.rejected = max(self.rejected, int(kv.value))


class Zed2JumpFault:
    """The fault as one test method; the TestCase it is mixed into sets ``z = Zed2Relay()`` first."""

    # ------------------------------------------------------------ helpers
    def wait_for(self, predicate, timeout):
        return rbd_testkit.wait_for(predicate, timeout, abort=rospy.is_shutdown)

    def speed(self):
        z = self.z
        with z.lock:
            return z.truth[-1][2] if z.truth else 0.0

    def record(self, **result):
        result["fault"] = "zed2_jump"
        a1_monitor.report_fault_result(result)

    # ------------------------------------------------------------ the fault
    def test_zed2_jump(self):
        g = rospy.get_param
        jump = float(g("~jump", 1.0))
        jump_delay = float(g("~jump_delay", 1.0))
        jump_duration = float(g("~jump_duration", 8.0))
        max_pose_error = float(g("~max_pose_error", 0.08))
        max_path_deviation = float(g("~max_path_deviation", 0.25))
        max_speed = float(g("~max_speed", 0.45))
        goal_tolerance = float(g("~goal_tolerance", 0.1))

        z = self.z
        self.assertTrue(self.wait_for(lambda: z.state and z.truth and z.relayed > 10, 90.0), "system not up")
        self.assertTrue(
            self.wait_for(lambda: len(z.pose_errors) > 20, 30.0), "no /rbd_localization/pose from the relayed ZED2"
        )
        # Known state: the path of a trick before this one (the smoke test's spin) is not this walk's.
        self.assertTrue(self.wait_for(lambda: z.state in ("EMERGENCY_STOP", "WAITING_FOR_GESTURE"), 90.0), z.state)
        with z.lock:
            del z.path[:]
        # Release the e-stop and show "walk" until the robot walks.
        rospy.wait_for_service("/rbd_controller/em_stop", 30.0)
        em_stop = rospy.ServiceProxy("/rbd_controller/em_stop", SetBool)
        last_gesture = [0.0]

        def walking():  # (the release and the gesture are sent from the predicate until the robot walks)
            if z.state == "EXECUTING" and self.speed() > 0.08:
                return True
            if z.state == "EMERGENCY_STOP":
                em_stop(False)
            if z.state == "WAITING_FOR_GESTURE" and time.monotonic() - last_gesture[0] > 0.4:
                z.gesture.publish(String("walk"))
                last_gesture[0] = time.monotonic()
            return False

        self.assertTrue(self.wait_for(walking, 45.0), "robot never walked (state %r)" % z.state)
        t_start = rospy.get_time()
        rejected_before = z.rejected
        time.sleep(jump_delay)
        # Sideways to the walk (+y): a controller following the jumped pose would lunge off the path.
        with z.lock:
            z.offset = (0.0, jump)
        t_jump = rospy.get_time()
        time.sleep(jump_duration)
        with z.lock:
            z.offset = (0.0, 0.0)
        t_clear = rospy.get_time()
        finished = self.wait_for(lambda: z.state == "WAITING_FOR_GESTURE", 60.0)
        reports = z.pose0_reports
        # the EKF's rejected count up to now: one more pose0 diagnostics report (1 Hz)
        self.assertTrue(self.wait_for(lambda: z.pose0_reports > reports, 5.0), "no EKF diagnostics after the trick")
        t_end = rospy.get_time()

        with z.lock:
            start = z.truth[bisect.bisect_left(z.truth_t, t_start) - 1]
            path = [(start[0], start[1])] + list(z.path)  # from where the trick started
            truth = [(t, s) for t, s in zip(z.truth_t, z.truth) if t_start <= t <= t_end]
            errors = [e for t, e in z.pose_errors if t_start <= t <= t_end]
        self.assertTrue(len(path) > 1, "no planned path on /rbd_controller/path")
        self.assertTrue(truth and errors, "no ground truth / localization pose recorded")
        deviation = max(distance_to_polyline(s[0], s[1], path) for _t, s in truth)
        top_speed = max(s[2] for _t, s in truth)
        pose_error = max(errors)
        final = truth[-1][1]
        goal_error = math.hypot(final[0] - path[-1][0], final[1] - path[-1][1])
        self.record(
            jump_m=jump,
            jump_s=round(t_clear - t_jump, 2),
            max_pose_error_m=round(pose_error, 3),
            max_path_deviation_m=round(deviation, 3),
            max_speed_mps=round(top_speed, 3),
            zed_rejected=z.rejected - rejected_before,
            finished=finished,
            goal_error_m=round(goal_error, 3),
        )
        self.assertGreater(z.rejected, rejected_before, "the EKF never reported a rejected ZED2 sample")
        self.assertLessEqual(pose_error, max_pose_error, "localization followed the ZED2 jump")
        self.assertLessEqual(deviation, max_path_deviation, "the robot left the planned path (lunge)")
        self.assertLessEqual(top_speed, max_speed, "the robot moved faster than the limits")
        self.assertTrue(finished, "the trick did not complete after the jump (state %r)" % z.state)
        self.assertLessEqual(goal_error, goal_tolerance, "the trick ended away from its goal")

