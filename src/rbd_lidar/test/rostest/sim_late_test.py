#!/usr/bin/env python3
"""rbd_lidar with late clouds (issue 27) on the simulator: a box put down ahead of the walking robot.

sim_late.test makes the simulated OS1 publish every cloud 0.15 s after its capture and a seeded
20 % of them 0.3 s after it (stamps stay the capture times). This test walks the robot through the
real driver at 0.4 m/s and stops it whenever rbd_lidar calls /rbd_controller/collision with
``true`` (resumes on ``false``), as rbd_controller does. Contacts are measured on the simulator's
ground truth (/rbd_sim/ground_truth, footprint against the box: rbd_bringup.metrics).

Two scenes, one after the other (the robot walks through the lab room's free middle):
  drop:     walking +x, a 0.4 m box put down 0.5 m ahead of the footprint (inside the zone grown
            for the walk, outside the rest zone): stopped with clearance left.
  approach: turned to face -x, walking towards a box 1.4 m ahead: the grown zone (with the age of
            the cloud) reaches it first; stopped with clearance left. While walking, the zone the
            node judged (its marker) is larger than speed x reaction_time alone: the age term.
Numbers go to stdout (LATE_RESULT ...); ``age_aware:=false`` runs the same without the age term
(for the comparison in the README; the zone check is then skipped).
"""
import math
import statistics
import threading
import unittest

import rospy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import Float32
from std_srvs.srv import SetBool, SetBoolResponse
from visualization_msgs.msg import Marker

from rbd_bringup.metrics import box_ahead, footprint_box_clearance
from rbd_geometry.rotation import yaw_of
from rbd_msgs.msg import CollisionState
from rbd_msgs.srv import PlaceBox
from rbd_testkit import stays_unchanged, wait_for
from rbd_testkit.ros import run_rostest

SPEED = 0.4  # [m/s], forward
BOX = (0.4, 0.4, 0.4)  # size x, y, height [m]
REST_FRONT = 0.70  # rbd_lidar's zone_front (the zone is measured from the LiDAR in this test)
REACTION = 0.7  # rbd_lidar's reaction_time [s]


class SimLateTest(unittest.TestCase):
    """Late clouds, a walking robot, a box: ground-truth clearance."""

    @classmethod
    def setUpClass(cls) -> None:
        """Node, fake controller (collision service + cmd_vel), recorders."""
        rospy.init_node("sim_late_test")
        cls.age_aware = bool(rospy.get_param("~age_aware", True))
        cls.cloud_delay = float(rospy.get_param("~cloud_delay", 0.15))
        cls.late_fraction = float(rospy.get_param("~late_fraction", 0.2))
        cls.late_delay = float(rospy.get_param("~late_delay", 0.3))
        cls.lock = threading.Lock()
        cls.truth = []  # (t, x, y, yaw, vx)
        cls.calls = []  # (t, data)
        cls.states = []  # (t, collision, stale)
        cls.arrivals = []  # (t, age) of /ouster/points here
        cls.node_ages = []  # ~cloud_age
        cls.markers = []  # (t, front x of the judged zone, commanded vx)
        cls.blocked = False
        cls.cmd = Twist()
        cls.cmd_pub = rospy.Publisher("/cmd_vel", Twist, queue_size=5)
        rospy.Service("/rbd_controller/collision", SetBool, cls._collision)
        rospy.Subscriber("/rbd_sim/ground_truth", Odometry, cls._gt, queue_size=20)
        rospy.Subscriber("/rbd_lidar/state", CollisionState, cls._state, queue_size=50)
        rospy.Subscriber("/rbd_lidar/cloud_age", Float32, cls._age, queue_size=50)
        rospy.Subscriber("/rbd_lidar/zone_marker", Marker, cls._marker, queue_size=20)
        rospy.Subscriber("/ouster/points", PointCloud2, cls._cloud, queue_size=5, buff_size=2 ** 24)
        rospy.wait_for_service("/rbd_sim/place_box", 30.0)
        cls.place = rospy.ServiceProxy("/rbd_sim/place_box", PlaceBox)
        cls.timer = rospy.Timer(rospy.Duration(0.02), cls._send)

    # -- the fake controller ------------------------------------------------------------------
    @classmethod
    def _collision(cls, req: SetBool) -> SetBoolResponse:
        with cls.lock:
            cls.calls.append((rospy.get_time(), req.data))
            cls.blocked = req.data
        if req.data:
            cls.cmd_pub.publish(Twist())  # stop at once, not at the next tick
        return SetBoolResponse(success=True, message="")

    @classmethod
    def _send(cls, _event: object) -> None:
        with cls.lock:
            cmd = Twist() if cls.blocked else cls.cmd
        try:
            cls.cmd_pub.publish(cmd)
        except rospy.ROSException:
            pass  # shutting down: the publisher is closed

    def _command(self, vx: float = 0.0, wz: float = 0.0) -> None:
        t = Twist()
        t.linear.x, t.angular.z = vx, wz
        with self.lock:
            type(self).cmd = t

    # -- recorders ----------------------------------------------------------------------------
    @classmethod
    def _gt(cls, msg: Odometry) -> None:
        p = msg.pose.pose.position
        with cls.lock:
            cls.truth.append((rospy.get_time(), p.x, p.y, yaw_of(msg.pose.pose.orientation), msg.twist.twist.linear.x))

    @classmethod
    def _state(cls, msg: CollisionState) -> None:
        with cls.lock:
            cls.states.append((rospy.get_time(), msg.collision, msg.stale))

    @classmethod
    def _age(cls, msg: Float32) -> None:
        with cls.lock:
            cls.node_ages.append(msg.data)

    @classmethod
    def _marker(cls, msg: Marker) -> None:
        if msg.points:
            with cls.lock:
                cls.markers.append((rospy.get_time(), max(p.x for p in msg.points), cls.cmd.linear.x, cls.blocked))

    @classmethod
    def _cloud(cls, msg: PointCloud2) -> None:
        now = rospy.get_time()
        with cls.lock:
            cls.arrivals.append((now, now - msg.header.stamp.to_sec()))

    # -- helpers ------------------------------------------------------------------------------
    def _pose(self) -> tuple:
        with self.lock:
            return self.truth[-1][1:4]

    def _still(self, span: float = 0.5) -> bool:
        with self.lock:
            t_end = self.truth[-1][0]
            recent = [s for s in self.truth if s[0] > t_end - span]
        return len(recent) > 5 and all(abs(s[4]) < 0.02 for s in recent)

    def _wait_clear(self) -> None:
        def clear() -> bool:
            with self.lock:
                recent = self.states[-5:]
            return len(recent) == 5 and not any(c for _, c, _ in recent) and not self.blocked

        wait_for(clear, 20.0, what="rbd_lidar clear for 5 scans", abort=rospy.is_shutdown)

    def _face(self, yaw: float) -> None:
        """Turns on the spot to ``yaw`` (world) with the ground truth, then stands still."""
        def err() -> float:
            return math.atan2(math.sin(yaw - self._pose()[2]), math.cos(yaw - self._pose()[2]))

        deadline = rospy.get_time() + 15.0
        rate = rospy.Rate(50)  # the turn's control loop
        while abs(err()) > 0.04 and rospy.get_time() < deadline and not rospy.is_shutdown():
            e = err()
            self._command(wz=math.copysign(min(0.8, max(0.25, 1.5 * abs(e))), e))
            rate.sleep()
        self._command()
        wait_for(self._still, 5.0, what="standing still after the turn", abort=rospy.is_shutdown)
        self.assertLess(abs(err()), 0.08)

    def _clearance(self, t0: float, box: tuple) -> float:
        with self.lock:
            samples = [s for s in self.truth if s[0] >= t0]
        self.assertGreater(len(samples), 50)
        return min(footprint_box_clearance((s[1], s[2]), s[3], box[:2], box[2], BOX[:2]) for s in samples)

    def _put(self, name: str, gap: float) -> tuple:
        box = box_ahead(self._pose(), gap, BOX[:2])
        r = self.place(name=name, x=box[0], y=box[1], yaw=box[2], size_x=BOX[0], size_y=BOX[1], height=BOX[2],
                       remove=False)
        self.assertTrue(r.success, r.message)
        return box

    def _stopped_after(self, t0: float, timeout: float) -> float:
        """Waits for the first collision call after ``t0`` and the robot standing; its time."""
        def called() -> bool:
            with self.lock:
                return any(t > t0 and d for t, d in self.calls)

        wait_for(called, timeout, what="a collision call", abort=rospy.is_shutdown)
        wait_for(self._still, 5.0, what="the robot standing after the stop", abort=rospy.is_shutdown)
        with self.lock:
            return next(t for t, d in self.calls if t > t0 and d)

    # -- the test -----------------------------------------------------------------------------
    def test_box_ahead_of_the_walking_robot_with_late_clouds(self) -> None:
        """0 contacts with a box dropped 0.5 m ahead, and when walking towards one, with late clouds."""
        self._wait_clear()
        # drop: walking +x; the box lands 0.5 m ahead of the footprint once the walk is steady
        start = self._pose()
        self._command(vx=SPEED)

        def walking() -> bool:
            x, y, _ = self._pose()
            with self.lock:
                vx = self.truth[-1][4]
            return not self.blocked and vx > 0.9 * SPEED and math.hypot(x - start[0], y - start[1]) > 0.15

        wait_for(walking, 10.0, what="walking steadily", abort=rospy.is_shutdown)
        with self.lock:
            speed_at_drop = self.truth[-1][4]
        t_drop = rospy.get_time()
        bag = self._put("late_bag", 0.5)
        t_stop = self._stopped_after(t_drop, 3.0)
        # standing in front of it, still commanded forward: the hold keeps the stop, on fresh ground truth
        with self.lock:
            n = len(self.truth)

        def fresh() -> bool:
            with self.lock:
                return len(self.truth) > n + 5

        stays_unchanged(lambda: self._still(0.3), fresh, hold=1.0, what="the robot standing in front of the bag",
                        proof="fresh ground truth")
        self._command()
        drop_clearance = self._clearance(t_drop, bag)
        self.place(name="late_bag", remove=True)

        # approach: face -x and walk towards a box 1.4 m ahead (the age-grown zone meets it first)
        self._face(math.pi)
        self._wait_clear()
        wall = self._put("late_wall", 1.4)
        self._wait_clear()  # the box is beyond the rest zone
        t_walk = rospy.get_time()
        self._command(vx=SPEED)
        t_hit = self._stopped_after(t_walk, 10.0)
        self._command()
        approach_clearance = self._clearance(t_walk, wall)
        self.place(name="late_wall", remove=True)

        with self.lock:
            fronts = [f for t, f, vx, held in self.markers if t_walk + 0.3 < t < t_hit and vx == SPEED and not held]
            ages = [a for _, a in self.arrivals]
            node_ages = list(self.node_ages)
            stale = sum(1 for _, _, s in self.states if s)
        late = sum(1 for a in ages if a > self.late_delay - 0.02) / max(1, len(ages))
        max_age = float(rospy.get_param("/rbd_lidar/max_cloud_age", 0.5))
        judged = [a for a in node_ages if a <= max_age]  # (overtaken clouds are not judged either)
        front = statistics.median(fronts) if fronts else float("nan")
        print(
            "\nLATE_RESULT age_aware=%s drop_clearance_m=%.3f approach_clearance_m=%.3f speed_at_drop=%.3f "
            "drop_to_stop_s=%.2f zone_front_walking_m=%.3f (%d markers; rest+speed*reaction=%.3f) "
            "cloud_age_min=%.3f p50=%.3f max=%.3f late_fraction=%.2f node_judged_age_p50=%.3f "
            "older_than_max_cloud_age=%d/%d stale_states=%d"
            % (self.age_aware, drop_clearance, approach_clearance, speed_at_drop, t_stop - t_drop, front,
               len(fronts), REST_FRONT + SPEED * REACTION, min(ages), statistics.median(ages), max(ages), late,
               statistics.median(judged) if judged else float("nan"), len(node_ages) - len(judged), len(node_ages),
               stale)
        )
        # The clouds really were late (measured here, on arrival).
        self.assertGreater(len(ages), 50)
        self.assertGreater(min(ages), 0.9 * self.cloud_delay)
        if self.late_fraction > 0:
            self.assertTrue(0.5 * self.late_fraction < late < 1.75 * self.late_fraction, late)
        # The robot walked into both scenes at speed and was stopped by the zone, not by chance.
        self.assertGreater(speed_at_drop, 0.9 * SPEED)
        # Ground truth: no contact.
        self.assertGreater(drop_clearance, 0.0)
        self.assertGreater(approach_clearance, 0.0)
        if self.age_aware:
            # The zone judged while walking grew by speed x (reaction_time + age), age >= the delay.
            self.assertGreater(len(fronts), 3)
            self.assertGreater(front, REST_FRONT + SPEED * (REACTION + 0.8 * self.cloud_delay))


if __name__ == "__main__":
    run_rostest("rbd_lidar", "sim_late", SimLateTest)
