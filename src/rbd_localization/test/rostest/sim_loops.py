#!/usr/bin/env python3
"""Drives the simulated A1 round the thesis path and measures the localization against ground truth.

Path (thesis 4.1.1): (0,0) -> (1,0), turn 180 deg, -> (-1,0), turn 180 deg, -> (0,0) facing +x.
The robot is steered on ground truth (/rbd_sim/ground_truth), so the path itself is exact (or,
with ``steer="corrected"``, on /rbd_localization/pose, as the robot's own navigation would: then
the ground truth shows where the localization took it); at every loop end the corrected pose
(/rbd_localization/pose, map) and the EKF alone (/odometry/filtered, odom: what the pose would be
without map correction) are compared with the truth. Writes a JSON report (and, with --png, the
trajectories as a PNG like thesis Fig. 16/17).

Used by the rostest sim_loops.test (few loops, with assertions) and by hand for the 10 loops:
    rosrun rbd_localization sim_loops.py --loops 10 --out /tmp/loops.json --png /tmp/loops.png
"""

import argparse
import bisect
import collections
import json
import math
import sys
import threading

import rospy
from geometry_msgs.msg import PoseStamped, Twist
from nav_msgs.msg import Odometry

from rbd_geometry.rotation import yaw_of
from rbd_testkit import wait_for

VX_MAX, WZ_MAX = 0.3, 0.6  # thesis saturations (0.3 m/s, 36 deg/s)


def wrap(a):
    """Wrap an angle to [-pi, pi)."""
    return (a + math.pi) % (2 * math.pi) - math.pi


def relative(pose, origin):
    """Return (x, y, yaw) of pose in the frame of origin (both (x, y, yaw))."""
    dx, dy = pose[0] - origin[0], pose[1] - origin[1]
    c, s = math.cos(origin[2]), math.sin(origin[2])
    return c * dx + s * dy, -s * dx + c * dy, wrap(pose[2] - origin[2])


class Runner:
    """Steers on ground truth and records the three trajectories (and any extra odometry).

    map_origin: (x, y, yaw) of the map frame in world (None: map == world); the truth is recorded
    and compared in the map frame. steer: "truth" (default) or "corrected" (the localization's pose).
    """

    def __init__(self, extra_odometry=None, map_origin=None, steer="truth"):
        if steer not in ("truth", "corrected"):
            raise ValueError("steer must be 'truth' or 'corrected', got %r" % (steer,))
        self.map_origin = map_origin
        self.steer = steer
        self.lock = threading.Lock()
        self.truth = None
        self.est = None
        self.ekf = None
        self.tracks = {"truth": [], "corrected": [], "ekf": []}
        self.truth_history = collections.deque(maxlen=2000)  # (stamp [s], (x, y, yaw)), for stamp matching
        self.max_err = 0.0  # corrected pose vs the latest ground truth since the last loop end
        # Extra odometry topics (another filter's odom frame): compared with the truth after
        # aligning both at the first sample once driving starts.
        self.extra = {name: {"topic": topic, "first": None, "recording": False, "max_err": 0.0, "samples": 0,
                             "track": []} for name, topic in (extra_odometry or {}).items()}
        self.cmd = rospy.Publisher("/cmd_vel", Twist, queue_size=1)
        rospy.Subscriber("/rbd_sim/ground_truth", Odometry, self.on_truth, queue_size=5)
        rospy.Subscriber("/rbd_localization/pose", PoseStamped, self.on_est, queue_size=5)
        rospy.Subscriber("/odometry/filtered", Odometry, self.on_ekf, queue_size=5)
        for name, e in self.extra.items():
            rospy.Subscriber(e["topic"], Odometry, self.on_extra, callback_args=name, queue_size=5)

    def on_truth(self, msg):
        p = msg.pose.pose
        truth = (p.position.x, p.position.y, yaw_of(p.orientation))
        if self.map_origin is not None:
            truth = relative(truth, self.map_origin)
        with self.lock:
            self.truth = truth
            self.tracks["truth"].append(self.truth[:2])
            self.truth_history.append((msg.header.stamp.to_sec(), self.truth))

    def truth_at(self, stamp):
        """Return the ground truth sample nearest in time to stamp (lock held), or None."""
        if not self.truth_history:
            return None
        stamps = [h[0] for h in self.truth_history]
        i = bisect.bisect_left(stamps, stamp)
        near = [j for j in (i - 1, i) if 0 <= j < len(stamps)]
        best = min(near, key=lambda j: abs(stamps[j] - stamp))
        return self.truth_history[best][1] if abs(stamps[best] - stamp) < 0.1 else None

    def on_est(self, msg):
        with self.lock:
            self.est = (msg.pose.position.x, msg.pose.position.y, yaw_of(msg.pose.orientation))
            self.tracks["corrected"].append(self.est[:2])
            if self.truth is not None:
                self.max_err = max(self.max_err, math.hypot(self.est[0] - self.truth[0], self.est[1] - self.truth[1]))

    def on_ekf(self, msg):
        p = msg.pose.pose
        with self.lock:
            self.ekf = (p.position.x, p.position.y, yaw_of(p.orientation))
            self.tracks["ekf"].append(self.ekf[:2])

    def on_extra(self, msg, name):
        p = msg.pose.pose
        est = (p.position.x, p.position.y, yaw_of(p.orientation))
        with self.lock:
            e = self.extra[name]
            truth = self.truth_at(msg.header.stamp.to_sec())  # same instant, not the latest message
            if not e["recording"] or truth is None:
                return
            if e["first"] is None:
                e["first"] = (est, truth)
            (ex, ey, eyaw), (tx, ty, tyaw) = e["first"]
            rel_est = relative(est, (ex, ey, eyaw))
            rel_truth = relative(truth, (tx, ty, tyaw))
            err = math.hypot(rel_est[0] - rel_truth[0], rel_est[1] - rel_truth[1])
            e["max_err"] = max(e["max_err"], err)
            e["samples"] += 1
            e["track"].append(rel_est[:2])
            e.setdefault("errors", []).append((msg.header.stamp.to_sec(), err, rel_est, rel_truth))
            e["final_err"] = err

    def start_extra(self):
        """Align the extra odometry with the truth at their next samples and record from then on."""
        with self.lock:
            for e in self.extra.values():
                e["first"], e["recording"], e["max_err"], e["samples"], e["track"] = None, True, 0.0, 0, []
                e["errors"] = []

    def send(self, vx, wz, vy=0.0):
        t = Twist()
        t.linear.x, t.linear.y, t.angular.z = vx, vy, wz
        self.cmd.publish(t)

    def steer_pose(self):
        """The pose the steering follows (lock held): the truth or the corrected pose (map)."""
        return self.truth if self.steer == "truth" else self.est

    def _steer(self, command, timeout):
        """At 20 Hz until command(x, y, yaw) on steer_pose returns None or timeout: send its
        (vx, wz[, vy]); then stop."""
        rate = rospy.Rate(20)
        end = rospy.Time.now() + rospy.Duration(timeout)
        while not rospy.is_shutdown() and rospy.Time.now() < end:
            with self.lock:
                pose = self.steer_pose()
            cmd = command(*pose)
            if cmd is None:
                break
            self.send(*cmd)
            rate.sleep()
        self.stop()

    def go_to(self, gx, gy, timeout=40.0):
        """Walk to (gx, gy): turn towards it, then P control on distance (on steer_pose)."""
        def command(x, y, yaw):
            dx, dy = gx - x, gy - y
            rho = math.hypot(dx, dy)
            if rho < 0.02:
                return None
            gamma = wrap(math.atan2(dy, dx) - yaw)
            if abs(gamma) > math.pi / 2:  # goal behind: walk backwards
                gamma = wrap(gamma + math.pi)
                sign = -1.0
            else:
                sign = 1.0
            return sign * min(VX_MAX, 2.5 * rho * math.cos(gamma)), max(-WZ_MAX, min(WZ_MAX, 2.0 * gamma))
        self._steer(command, timeout)

    def turn_to(self, goal_yaw, timeout=30.0):
        def command(_x, _y, yaw):
            err = wrap(goal_yaw - yaw)
            if abs(err) < 0.01:
                return None
            return 0.0, max(-WZ_MAX, min(WZ_MAX, 1.5 * err))
        self._steer(command, timeout)

    def settle_at(self, gx, gy, tol=0.01, timeout=10.0):
        """Step onto (gx, gy) without turning (forward and sideways P control on steer_pose).

        An in-place turn of the A1 creeps (the simulated drift: 0.4 m per 180 deg), so a turn at
        the goal leaves the robot off it; this puts it back as a robot's position controller would.
        """
        def command(x, y, yaw):
            dx, dy = gx - x, gy - y
            if math.hypot(dx, dy) < tol:
                return None
            c, s = math.cos(yaw), math.sin(yaw)
            ex, ey = c * dx + s * dy, -s * dx + c * dy
            return max(-0.15, min(0.15, 1.5 * ex)), 0.0, max(-0.15, min(0.15, 1.5 * ey))
        self._steer(command, timeout)

    def stop(self):
        rate = rospy.Rate(20)  # ten zero commands, at the walking loops' pace
        for _ in range(10):
            self.send(0.0, 0.0)
            rate.sleep()

    def errors(self):
        with self.lock:
            tx, ty, tyaw = self.truth
            out = {"truth": [tx, ty, tyaw]}
            for name, pose in (("corrected", self.est), ("ekf", self.ekf)):
                if pose is None:
                    out[name] = None
                    continue
                out[name] = {"pos_err": math.hypot(pose[0] - tx, pose[1] - ty),
                             "yaw_err_deg": abs(math.degrees(wrap(pose[2] - tyaw)))}
            out["corrected_max_during_loop"] = self.max_err
            self.max_err = 0.0
        return out

    def wait_ready(self, timeout=60.0):
        def ready():
            with self.lock:
                return bool(self.truth and self.est and self.ekf)

        return wait_for(ready, timeout, 0.2, abort=rospy.is_shutdown)

    def extra_aligned(self):
        """True once every extra odometry has its first recorded sample (aligned with the truth)."""
        with self.lock:
            return all(e["first"] is not None for e in self.extra.values())


def drive_loop(r, settle=False):
    """One loop of the thesis path with runner r, ending at (0, 0) facing +x.

    settle: after the last turn, step back onto (0, 0) sideways (Runner.settle_at), so that the
    loop ends where it started also on a robot that creeps while turning.
    """
    r.go_to(1.0, 0.0)
    r.turn_to(math.pi)
    r.go_to(-1.0, 0.0)
    r.turn_to(0.0)
    r.go_to(0.0, 0.0)
    r.turn_to(0.0)
    if settle:
        r.settle_at(0.0, 0.0)
    rospy.sleep(1.0)


def drive_loops(r, loops, settle=False):
    """Drive `loops` loops with runner r; return {"loops": [errors at each loop end]}.

    Each entry also has "start_truth" and "truth_closure" [m]: how far the loop's end is from its
    start on ground truth (what matters when steering on the corrected pose).
    """
    report = {"loops": []}
    for i in range(loops):
        with r.lock:
            start = r.truth
        drive_loop(r, settle)
        e = r.errors()
        e["loop"] = i + 1
        e["start_truth"] = list(start)
        e["truth_closure"] = math.hypot(e["truth"][0] - start[0], e["truth"][1] - start[1])
        report["loops"].append(e)
        rospy.loginfo("loop %d: %s", i + 1, json.dumps(e))
    return report


def run(loops, settle=4.0, extra_odometry=None):
    """Drive `loops` loops; return the per-loop error report.

    extra_odometry: {name: topic} of further odometry (e.g. another filter configuration),
    reported under report["extra"][name] with its largest and final error against the truth.
    """
    r = Runner(extra_odometry)
    if not r.wait_ready():
        raise RuntimeError("no ground truth / pose / odometry")
    rospy.sleep(settle)  # map built while standing
    r.start_extra()
    if not wait_for(r.extra_aligned, 10.0, 0.05, abort=rospy.is_shutdown):
        raise RuntimeError("no sample of the extra odometry %s" % sorted(r.extra))
    report = drive_loops(r, loops)
    with r.lock:  # subscribers keep appending
        report["tracks"] = {k: list(v) for k, v in r.tracks.items()}
        report["extra"] = {name: {"max_err": e["max_err"], "final_err": e.get("final_err"), "samples": e["samples"],
                                  "track": list(e["track"]), "errors": list(e.get("errors", []))}
                           for name, e in r.extra.items()}
    return report


def save_png(report, path):
    """Plot truth, corrected and EKF-only trajectories."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5))
    for name, style in (("ekf", "r-"), ("corrected", "b-"), ("truth", "k--")):
        pts = report["tracks"][name]
        pts = [p for p in pts if len(p) == 2]
        if pts:
            ax.plot([p[0] for p in pts], [p[1] for p in pts], style, lw=0.7,
                    label={"truth": "ground truth", "ekf": "EKF only (no map correction)",
                           "corrected": "with map correction"}[name])
    last = report["loops"][-1]
    ax.set_title("%d loops: final error %.3f m corrected, %.3f m EKF only"
                 % (len(report["loops"]), last["corrected"]["pos_err"], last["ekf"]["pos_err"]))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.axis("equal")
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--loops", type=int, default=10)
    parser.add_argument("--out", default="")
    parser.add_argument("--png", default="")
    args = parser.parse_args(rospy.myargv(sys.argv)[1:])
    rospy.init_node("sim_loops")
    report = run(args.loops)
    if args.out:
        with open(args.out, "w") as f:
            json.dump(report, f)
    if args.png:
        save_png(report, args.png)
    print(json.dumps(report["loops"][-1]))


if __name__ == "__main__":
    main()
