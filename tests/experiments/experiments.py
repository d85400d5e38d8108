#!/usr/bin/env python3
"""The thesis experiments (§4) in the simulator, measured on ground truth, drawn as PNGs.

Usage: experiments.py --stack {control,safety} --out DIR [--short] NAME...

- stack `control` (mock A1 + driver; the position controller is added after the steps):
  `step` (Fig. 18), `rotation` (Fig. 19/20), `path` (Fig. 21, full runs only);
- stack `safety` (`rbd_bringup sim.launch`, localization off, no RViz/GUI):
  `zone` (Fig. 22), `boundary` (Fig. 23), `reaction` (software reaction time).

Each experiment writes DIR/<name>.json (its results) and DIR/fig*.png. `run_all` runs both
stacks and builds the table. The position experiments reuse `rbd_pos_controller`'s
`run_experiment`; the reaction time reuses the demo's LCM monitor and report maths.
"""

import argparse
import functools
import json
import math
import os
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)

import analysis  # noqa: E402
import matplotlib  # noqa: E402
import thesis  # noqa: E402

import rbd_testkit  # noqa: E402
from rbd_testkit import RosEnv, free_port  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from rbd_geometry.rotation import yaw_of, yaw_to_quat  # noqa: E402

DPI = 80


def log(msg):
    """One progress line."""
    print("[experiments] %s" % msg, flush=True)


# The kit's wait_for, polling at 50 Hz.
wait_for = functools.partial(rbd_testkit.wait_for, step=0.02)


class Truth:
    """Ground truth of the mock A1: (t, x, y, yaw, vx, vy, wz) with the twist in the body frame."""

    def __init__(self):
        import rospy
        from nav_msgs.msg import Odometry

        self.lock = threading.Lock()
        self.samples = []
        rospy.Subscriber("/rbd_sim/ground_truth", Odometry, self._on, queue_size=100)

    def _on(self, msg):
        p, tw = msg.pose.pose.position, msg.twist.twist
        with self.lock:
            self.samples.append((msg.header.stamp.to_sec(), p.x, p.y, yaw_of(msg.pose.pose.orientation),
                                 tw.linear.x, tw.linear.y, tw.angular.z))
            if len(self.samples) > 30000:
                del self.samples[:10000]

    def last(self):
        """Latest sample or None."""
        with self.lock:
            return self.samples[-1] if self.samples else None

    def between(self, t0, t1):
        """Samples with t0 <= t <= t1."""
        with self.lock:
            return [s for s in self.samples if t0 <= s[0] <= t1]


def save(fig, out, name):
    """Write a figure as a small PNG; returns the path."""
    path = os.path.join(out, name)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


# --------------------------------------------------------------------------------------------
# Fig. 18: velocity steps in x, y and yaw (open loop, straight to the driver)
# --------------------------------------------------------------------------------------------
STEPS = [("x", 0.3, "m/s"), ("y", 0.12, "m/s"), ("yaw", math.radians(36.0), "rad/s")]


def exp_step(ctx):
    """Step responses on /cmd_vel with Table 2's saturations as amplitudes."""
    import rospy
    from geometry_msgs.msg import Twist

    pub = rospy.Publisher("/cmd_vel", Twist, queue_size=1)
    if not wait_for(lambda: pub.get_num_connections() > 0 and ctx.truth.last() is not None, 30):
        raise RuntimeError("no driver on /cmd_vel or no ground truth")
    pre, dur, post = (0.5, 2.0, 0.6) if ctx.short else (1.0, 4.0, 1.5)
    rate = 50.0
    result, traces = {}, {}

    def hold(twist, seconds):
        end = time.monotonic() + seconds
        pace = rospy.Rate(rate)
        while time.monotonic() < end:
            pub.publish(twist)
            pace.sleep()

    for axis, amp, unit in STEPS:
        hold(Twist(), pre)
        step = Twist()
        if axis == "x":
            step.linear.x = amp
        elif axis == "y":
            step.linear.y = amp
        else:
            step.angular.z = amp
        t_step = rospy.get_time()
        hold(step, dur)
        t_end = rospy.get_time()
        hold(Twist(), post)
        samples = ctx.truth.between(t_step - pre, t_end + post)
        start = min(ctx.truth.between(t_step - 0.2, t_step), key=lambda s: abs(s[0] - t_step))
        col = {"x": 4, "y": 5, "yaw": 6}[axis]
        vel = [(s[0], s[col]) for s in samples]
        m = analysis.step_metrics(vel, t_step, t_end, amp)
        # Output position / angle in the frame of the robot at the step (integrating behaviour).
        c, sn = math.cos(start[3]), math.sin(start[3])
        if axis == "yaw":
            u = analysis.unwrap([start[3]] + [s[3] for s in samples])
            pos = [(s[0], a - u[0]) for s, a in zip(samples, u[1:])]
        else:
            pos = [(s[0], (c * (s[1] - start[1]) + sn * (s[2] - start[2])) if axis == "x"
                    else (-sn * (s[1] - start[1]) + c * (s[2] - start[2]))) for s in samples]
        half = [p for p in pos if t_step + 0.5 * dur <= p[0] <= t_end]
        m["amplitude"] = amp
        m["unit"] = unit
        m["ramp_slope_ratio"] = analysis.ramp_slope(half) / amp
        result[axis] = m
        traces[axis] = (t_step, t_end, vel, pos)
        log("step %s %.3f %s: dead %.3f s, rise %s s, overshoot %.1f %%, ss error %.1f %%, slope/cmd %.2f" % (
            axis, amp, unit, m["dead_time_s"] or float("nan"), "%.3f" % m["rise_time_s"] if m["rise_time_s"] else "n/a",
            m["overshoot_pct"], m["steady_state_error_pct"], m["ramp_slope_ratio"]))

    fig, axes = plt.subplots(1, 3, figsize=(10, 3.0))
    for ax, (axis, amp, unit) in zip(axes, STEPS):
        t_step, t_end, vel, pos = traces[axis]
        ts = [t - t_step for t, _ in vel]
        ax.step([ts[0], 0, t_end - t_step, ts[-1]], [0, amp, 0, 0], where="post", color="k", lw=1, label="input")
        ax.plot(ts, [v for _, v in vel], color="tab:blue", lw=1, label="output velocity")
        ax2 = ax.twinx()
        ax2.plot([t - t_step for t, _ in pos], [p for _, p in pos], color="tab:orange", lw=1,
                 label="output %s" % ("angle [rad]" if axis == "yaw" else "position [m]"))
        ax.set_title("%s step (dead time %.0f ms)" % (axis, 1000 * (result[axis]["dead_time_s"] or float("nan"))),
                     fontsize=9)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("velocity [%s]" % unit, fontsize=8)
        ax2.set_ylabel("angle [rad]" if axis == "yaw" else "position [m]", fontsize=8)
        if axis == "x":
            ax.legend(loc="upper left", fontsize=7)
            ax2.legend(loc="lower right", fontsize=7)
    result["png"] = save(fig, ctx.out, "fig18_step.png")
    return result


# --------------------------------------------------------------------------------------------
# Fig. 19/20/21: the position controller, through rbd_pos_controller's run_experiment
# --------------------------------------------------------------------------------------------
def start_pos_controller(ctx):
    """Add rbd_pos_controller (pose = ground truth) to the control stack once."""
    import rospy

    if ctx.pos_started:
        return
    ctx.stack.launch("rbd_pos_controller", "rbd_pos_controller.launch", "pose_topic:=/rbd_sim/ground_truth_pose",
                     "profile:=sim_tuned", name="pos_controller")
    rospy.wait_for_service("/rbd_pos_controller/set_position", timeout=60.0)
    ctx.pos_started = True


def run_experiment(ctx, name, sub, label):
    """rosrun rbd_pos_controller run_experiment NAME into OUT/runs/SUB; returns (metrics, RunLog)."""
    from rbd_pos_controller.runlog import RunLog

    out = os.path.join(ctx.out, "runs", sub)
    proc = subprocess.run(["rosrun", "rbd_pos_controller", "run_experiment", name, "--out", out, "--label", label],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=180)
    if proc.returncode != 0:
        raise RuntimeError("run_experiment %s failed:\n%s" % (name, proc.stdout[-3000:]))
    with open(os.path.join(out, name + "_metrics.json")) as fh:
        metrics = json.load(fh)
    return metrics, RunLog.load(os.path.join(out, name + ".json"))


def exp_rotation(ctx):
    """180 deg in place with and without the position hold; the mock A1 drifts sideways."""
    import rospy

    start_pos_controller(ctx)
    runs = {}
    for key, on in (("without_correction", False), ("with_correction", True)):
        rospy.set_param("/rbd_pos_controller/rotation_x_control", on)
        rospy.set_param("/rbd_pos_controller/rotation_y_control", on)
        metrics, run = run_experiment(ctx, "rotation180", key, key.replace("_", " "))
        metrics["peak_wz_deg_s"] = max(abs(math.degrees(c[3])) for c in run.cmds) if run.cmds else None
        runs[key] = (metrics, run)
        log("rotation 180 %s: drift %.3f m, %.1f s, peak wz %.1f deg/s" % (
            key, metrics["drift_from_start_m"], metrics["total_time_s"], metrics["peak_wz_deg_s"] or 0.0))
    rospy.set_param("/rbd_pos_controller/rotation_x_control", True)
    rospy.set_param("/rbd_pos_controller/rotation_y_control", True)

    metrics, run = runs["with_correction"]
    t0 = run.goals[0][0]
    fig, ax = plt.subplots(figsize=(6, 3.0))
    yaws = analysis.unwrap([p[3] - run.start[2] for p in run.poses])
    ax.plot([p[0] - t0 for p in run.poses], [math.degrees(a) for a in yaws], color="tab:orange", label="yaw [deg]")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("yaw [deg]")
    ax2 = ax.twinx()
    ax2.plot([c[0] - t0 for c in run.cmds], [math.degrees(c[3]) for c in run.cmds], color="tab:blue",
             label="commanded wz [deg/s]")
    ax2.set_ylabel("wz [deg/s]")
    ax.set_title("Fig. 19: 180 deg with the saturated P controller (peak %.0f deg/s)" % metrics["peak_wz_deg_s"],
                 fontsize=9)
    ax.legend(loc="center right", fontsize=7)
    ax2.legend(loc="lower right", fontsize=7)
    png19 = save(fig, ctx.out, "fig19_rotation.png")

    fig, ax = plt.subplots(figsize=(4.5, 4.0))
    for key, color in (("without_correction", "tab:red"), ("with_correction", "tab:green")):
        m, r = runs[key]
        c, s = math.cos(-r.start[2]), math.sin(-r.start[2])
        xs = [c * (p[1] - r.start[0]) - s * (p[2] - r.start[1]) for p in r.poses]
        ys = [s * (p[1] - r.start[0]) + c * (p[2] - r.start[1]) for p in r.poses]
        ax.plot(xs, ys, color=color, label="%s: %.3f m" % (key.replace("_", " "), m["drift_from_start_m"]))
        ax.plot(xs[-1:], ys[-1:], "o", color=color)
    ax.plot([0], [0], "k+", ms=12, label="start")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x in start frame [m]")
    ax.set_ylabel("y in start frame [m]")
    ax.set_title("Fig. 20: position after 180 deg", fontsize=9)
    ax.legend(fontsize=7)
    png20 = save(fig, ctx.out, "fig20_drift.png")
    result = {k: v[0] for k, v in runs.items()}
    result["png"] = [png19, png20]
    return result


def exp_path(ctx):
    """The thesis path (0,0) -> (1,0) -> (-1,0) -> (0,0) relative to the start pose."""
    start_pos_controller(ctx)
    metrics, run = run_experiment(ctx, "thesis_path", "path", "thesis path")
    log("path: max deviation %.3f m, %.1f s, final error %.3f m" % (
        metrics["max_deviation_m"], metrics["total_time_s"], metrics["final_position_error_m"]))
    c, s = math.cos(-run.start[2]), math.sin(-run.start[2])

    def local(x, y):
        return c * (x - run.start[0]) - s * (y - run.start[1]), s * (x - run.start[0]) + c * (y - run.start[1])

    fig, (ax, axv) = plt.subplots(1, 2, figsize=(9, 3.2), gridspec_kw={"width_ratios": [1.2, 1]})
    plan = [(0.0, 0.0)] + [local(g[1], g[2]) for g in run.goals]
    ax.plot([p[0] for p in plan], [p[1] for p in plan], "k--", lw=1, label="planned")
    driven = [local(p[1], p[2]) for p in run.poses]
    ax.plot([p[0] for p in driven], [p[1] for p in driven], color="tab:blue", lw=1.2, label="driven (ground truth)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("Fig. 21a: max deviation %.3f m, final %.3f m" % (
        metrics["max_deviation_m"], metrics["final_position_error_m"]), fontsize=9)
    ax.legend(fontsize=7)
    t0 = run.goals[0][0]
    for i, (lab, color) in enumerate((("vx [m/s]", "tab:blue"), ("vy [m/s]", "tab:green"), ("wz [rad/s]", "tab:red"))):
        axv.plot([cmd[0] - t0 for cmd in run.cmds], [cmd[1 + i] for cmd in run.cmds], color=color, lw=1, label=lab)
    axv.set_xlabel("t [s]")
    axv.set_title("Fig. 21b: commanded velocities (%.1f s)" % metrics["total_time_s"], fontsize=9)
    axv.legend(fontsize=7)
    metrics["png"] = save(fig, ctx.out, "fig21_path.png")
    metrics["full"] = True
    return metrics


# --------------------------------------------------------------------------------------------
# Fig. 22/23 and the reaction time: the LiDAR zone on the full simulated system
# --------------------------------------------------------------------------------------------
class Zone:
    """Places a cylinder around a frame (default the LiDAR) and reads whether the scans after it trip the zone.

    Args:
        frame: the TF frame distances and angles are measured from: ``os_sensor`` (the LiDAR, as the
            thesis measured) or a body frame such as ``collision_zone`` (the zone's origin).
    """

    def __init__(self, frame="os_sensor"):
        import rospy
        import tf2_ros

        from rbd_msgs.msg import CollisionState
        from rbd_msgs.srv import PlaceObstacle

        self.lock = threading.Lock()
        self.states = []
        rospy.Subscriber("/rbd_lidar/state", CollisionState, self._on, queue_size=50)
        rospy.wait_for_service("/rbd_sim/place_obstacle", timeout=60.0)
        self.place = rospy.ServiceProxy("/rbd_sim/place_obstacle", PlaceObstacle)
        self.threshold = int(rospy.get_param("/rbd_lidar/point_threshold", 5))
        self.zone = tuple(float(rospy.get_param("/rbd_lidar/zone_" + s)) for s in ("front", "back", "left", "right"))
        self.blind = float(rospy.get_param("/rbd_lidar/blind_zone", 0.3))
        self.scan_period = 1.0 / float(rospy.get_param("/rbd_lidar/scan_rate", 10.0))
        self.frame = frame
        self._buf = tf2_ros.Buffer()
        self._listener = tf2_ros.TransformListener(self._buf)
        self.locate()
        if not wait_for(lambda: self.states, 30.0):
            raise RuntimeError("no /rbd_lidar/state")

    def locate(self):
        """Read where the frame is now (``origin``, ``yaw`` in the world).

        The pose is read once here, not per probe: call this again once the robot has moved (an
        experiment that walked it leaves it elsewhere than where the prober was created).
        """
        import rospy

        tf = self._buf.lookup_transform("world", self.frame, rospy.Time(0), rospy.Duration(30.0)).transform
        self.origin = (tf.translation.x, tf.translation.y)
        self.yaw = yaw_of(tf.rotation)

    def mount(self, parent):
        """(x, y) [m] of the frame in `parent` (e.g. base_link), from TF."""
        import rospy

        t = self._buf.lookup_transform(parent, self.frame, rospy.Time(0), rospy.Duration(10.0)).transform.translation
        return t.x, t.y

    def _on(self, msg):
        with self.lock:
            self.states.append(msg)
            del self.states[:-200]

    def world(self, dist, angle):
        """World position of a point at dist [m], angle [rad] from the frame's origin."""
        a = self.yaw + angle
        return self.origin[0] + dist * math.cos(a), self.origin[1] + dist * math.sin(a)

    def tripped(self, since, scans=2):
        """Whether the scans-th scan stamped after `since` has >= point_threshold critical points."""
        import rospy

        def later():
            with self.lock:
                return [s for s in self.states if s.header.stamp.to_sec() > since and not s.stale and not s.error]

        if not wait_for(later, 5.0) or not wait_for(lambda: len(later()) >= scans, 5.0):
            raise RuntimeError("no LiDAR scans after %.2f (now %.2f)" % (since, rospy.get_time()))
        return sum(later()[scans - 1].points) >= self.threshold

    def probe(self, name, dist, angle, radius):
        """Put the cylinder's axis at (dist, angle) from the LiDAR; True when the zone trips."""
        import rospy

        x, y = self.world(dist, angle)
        if not self.place(name=name, x=x, y=y, radius=radius, height=1.7, remove=False).success:
            raise RuntimeError("place_obstacle refused")
        return self.tripped(rospy.get_time())

    def state_flips(self, name, dist, angle, radius):
        """Whether the published collision state itself goes true with the cylinder at dist."""
        import rospy

        x, y = self.world(dist, angle)
        self.place(name=name, x=x, y=y, radius=radius, height=1.7, remove=False)
        since = rospy.get_time()

        def collided():
            with self.lock:
                return any(s.collision for s in self.states if s.header.stamp.to_sec() > since)

        return wait_for(collided, 4 * self.scan_period + 0.5)

    def remove(self, name):
        """Take the cylinder away."""
        self.place(name=name, remove=True)

    def clear(self):
        """True when the zone is empty now."""
        import rospy

        return not self.tripped(rospy.get_time(), scans=1)


def flip_distance(zone, name, angle, radius, expected, resolution):
    """Bisection for the cylinder centre distance at which the zone starts tripping.

    The near end keeps the cylinder's surface just outside the LiDAR's blind zone.
    """
    near = max(expected - 0.25, radius + zone.blind + 0.02)
    return analysis.find_flip(lambda d: zone.probe(name, d, angle, radius), near, expected + 0.25, resolution)


def exp_zone(ctx):
    """Fig. 22: a person-sized cylinder (r = 0.2 m) at angles around the robot; where the zone trips."""
    zone = ctx.zone()
    radius = 0.2
    angles = [0, 90, 180, 270] if ctx.short else list(range(0, 360, 20))
    points = []
    for deg in angles:
        a = math.radians(deg)
        expected = analysis.expected_trigger_distance(a, radius, zone.zone)
        measured = flip_distance(zone, "fig22", a, radius, expected, 0.02 if ctx.short else 0.01)
        confirmed = measured is not None and zone.state_flips("fig22", measured - 0.02, a, radius)
        points.append({"angle_deg": deg, "expected_centre_m": expected, "measured_centre_m": measured,
                       "error_m": None if measured is None else measured - expected, "state_confirmed": confirmed})
        log("zone %3d deg: trips at centre %.3f m, expected %.3f m" % (deg, measured or float("nan"), expected))
    zone.remove("fig22")
    errors = [abs(p["error_m"]) for p in points if p["error_m"] is not None]
    result = {"radius_m": radius, "zone_m": list(zone.zone), "points": points,
              "max_abs_error_m": max(errors) if len(errors) == len(points) else None}

    fig, ax = plt.subplots(figsize=(4.6, 4.6))
    outline = analysis.zone_outline(zone.zone)
    ax.plot([p[0] for p in outline], [p[1] for p in outline], "k-", lw=1.2, label="configured zone")
    ring = [math.radians(d) for d in range(0, 361, 2)]
    exp_pts = [(analysis.expected_trigger_distance(a, radius, zone.zone) - radius, a) for a in ring]
    ax.plot([d * math.cos(a) for d, a in exp_pts], [d * math.sin(a) for d, a in exp_pts], "k:", lw=1,
            label="expected trigger (r=%.1f m)" % radius)
    for p in points:
        if p["measured_centre_m"] is None:
            continue
        a, d = math.radians(p["angle_deg"]), p["measured_centre_m"] - radius
        ax.plot([d * math.cos(a)], [d * math.sin(a)], "o", color="tab:red", ms=5)
        ax.add_patch(plt.Circle(((d + radius) * math.cos(a), (d + radius) * math.sin(a)), radius, fill=False,
                                color="tab:red", lw=0.4, alpha=0.4))
    ax.plot([], [], "o", color="tab:red", label="measured trigger (nearest surface)")
    blind = plt.Circle((0, 0), 0.3, color="0.8", label="blind zone 0.3 m")
    ax.add_patch(blind)
    ax.set_aspect("equal")
    ax.set_xlim(-1.2, 1.4)
    ax.set_ylim(-1.2, 1.2)
    ax.set_xlabel("x ahead of the LiDAR [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("Fig. 22: zone shape, max |error| %s" % (
        "%.0f mm" % (1000 * result["max_abs_error_m"]) if result["max_abs_error_m"] is not None else "n/a"),
        fontsize=9)
    ax.legend(fontsize=6, loc="lower left")
    result["png"] = save(fig, ctx.out, "fig22_zone.png")
    return result


def exp_boundary(ctx):
    """Fig. 23: a wide target (r = 1 m cylinder, nearly flat) approaches each side; boundary vs set distance."""
    zone = ctx.zone()
    radius = 1.0
    sides = [("front", 0.0, zone.zone[0]), ("back", math.pi, zone.zone[1]), ("left", math.pi / 2, zone.zone[2]),
             ("right", -math.pi / 2, zone.zone[3])]
    out = []
    for side, angle, target in sides:
        flip = flip_distance(zone, "fig23", angle, radius, target + radius, 0.005)
        measured = None if flip is None else flip - radius
        out.append({"side": side, "target_m": target, "measured_m": measured})
        log("boundary %s: set %.0f mm, measured %s" % (side, target * 1000,
                                                        "n/a" if measured is None else "%.0f mm" % (measured * 1000)))
        zone.remove("fig23")
    result = {"sides": out, "tolerance_m": 0.08}
    fig, ax = plt.subplots(figsize=(5, 3.0))
    xs = range(len(out))
    ax.bar([x - 0.18 for x in xs], [1000 * s["target_m"] for s in out], 0.36, color="0.7", label="set distance")
    ax.bar([x + 0.18 for x in xs], [1000 * (s["measured_m"] or 0) for s in out], 0.36, color="tab:blue",
           label="measured boundary")
    ax.errorbar(list(xs), [1000 * s["target_m"] for s in out], yerr=80, fmt="none", ecolor="k", capsize=6,
                label="+-80 mm tolerance")
    for x, s in zip(xs, out):
        if s["measured_m"] is not None:
            ax.text(x + 0.18, 1000 * s["measured_m"] + 15, "%.0f" % (1000 * s["measured_m"]), ha="center", fontsize=8)
    ax.set_xticks(list(xs))
    ax.set_xticklabels([s["side"] for s in out])
    ax.set_ylabel("distance from the LiDAR [mm]")
    ax.set_title("Fig. 23: collision boundary accuracy", fontsize=9)
    ax.legend(fontsize=7, loc="upper right")
    ax.set_ylim(0, 950)
    result["png"] = save(fig, ctx.out, "fig23_boundary.png")
    return result


def exp_reaction(ctx):
    """Software reaction: the robot walks, a person appears 1 m ahead; scan -> zero HighCmd at the A1."""
    import rospy
    from geometry_msgs.msg import Pose
    from std_msgs.msg import String
    from std_srvs.srv import SetBool

    from rbd_bringup.demo_report import percentile, reaction_times
    from rbd_msgs.msg import PosControllerStatus as Status
    from rbd_msgs.srv import SetPosition

    sys.path.insert(0, os.path.join(ROOT, "tools"))
    from demo_monitor import Monitor  # the demo's LCM + ground-truth + state monitor

    zone = ctx.zone()
    monitor = Monitor(rospy.get_param("/rbd_sim/lcm_url"))
    status = {"v": ""}
    rospy.Subscriber("/rbd_pos_controller/status", String, lambda m: status.update(v=m.data), queue_size=10)

    def where():  # what the error of a failed wait reports
        return "(controller %s, position controller %r, states %s)" % (
            monitor.state or "silent", status["v"], " ".join(s for _, s in monitor.state_log[-8:]))

    try:
        if not monitor.wait_state(("EMERGENCY_STOP",), 60.0):
            raise RuntimeError("controller did not come up " + where())
        # The monitor's own ground-truth subscription (every trial reads monitor.pose at once).
        if not wait_for(lambda: monitor.pose is not None, 30.0):
            raise RuntimeError("no ground truth at the monitor within 30 s " + where())
        rospy.wait_for_service("/rbd_controller/em_stop", 30.0)
        rospy.ServiceProxy("/rbd_controller/em_stop", SetBool)(False)
        if not monitor.wait_state(("WAITING_FOR_GESTURE",), 30.0):
            raise RuntimeError("e-stop release did not reach WAITING_FOR_GESTURE " + where())
        set_position = rospy.ServiceProxy("/rbd_pos_controller/set_position", SetPosition)
        trials = 2 if ctx.short else 10
        done = 0
        for i in range(trials):
            if not wait_for(lambda: status["v"] == Status.IDLE and monitor.state == "WAITING_FOR_GESTURE", 20.0):
                log("reaction trial %d: robot not idle after 20 s %s" % (i + 1, where()))
            x, y, yaw = monitor.pose
            goal = Pose()
            goal.position.x, goal.position.y = x + 1.5 * math.cos(yaw), y + 1.5 * math.sin(yaw)
            _x, _y, goal.orientation.z, goal.orientation.w = yaw_to_quat(yaw)
            if not set_position(pose=goal).accepted:
                raise RuntimeError("trial %d: goal refused %s" % (i + 1, where()))
            if not wait_for(lambda: monitor.commands and monitor.commands[-1][1] > 0.1, 10.0):
                raise RuntimeError("trial %d: robot did not start walking %s" % (i + 1, where()))
            time.sleep(0.3 + 0.1 * (i % 3))  # different scan phases
            x, y, yaw = monitor.pose
            zone.place(name="visitor", x=x + 1.0 * math.cos(yaw), y=y + 1.0 * math.sin(yaw), radius=0.2, height=1.7,
                       remove=False)
            stopped = monitor.wait_state(("COLLISION_DETECTED",), 5.0)
            time.sleep(0.8)
            zone.remove("visitor")
            log("reaction trial %d: %s" % (i + 1, "stopped" if stopped else "NOT stopped"))
            done += int(stopped)
            # Back to the start of this trial (short way: no pre-rotation).
            wait_for(lambda: monitor.state == "WAITING_FOR_GESTURE" and status["v"] == Status.IDLE, 10.0)
            back = Pose()
            back.position.x, back.position.y = goal.position.x - 1.5 * math.cos(yaw), goal.position.y - 1.5 * math.sin(
                yaw)
            back.orientation = goal.orientation
            set_position(pose=back)
            wait_for(lambda: status["v"] == Status.RUNNING, 3.0)
            wait_for(lambda: status["v"] == Status.IDLE, 15.0)
        time.sleep(0.3)
        with monitor.lock:
            times = reaction_times(monitor.onsets, monitor.commands)
            commands = list(monitor.commands)
            onsets = list(monitor.onsets)
    finally:
        monitor.close()
    # Whole reaction incl. the simulated mechanics (the thesis' stopwatch figure): scan stamp ->
    # ground-truth body speed below 1 cm/s, for every onset while the robot was walking.
    stops = []
    for onset in onsets:
        truth = ctx.truth.between(onset - 0.05, onset + 3.0)
        if not truth or math.hypot(truth[0][4], truth[0][5]) < 0.05:
            continue
        still = next((s[0] for s in truth if s[0] > onset and math.hypot(s[4], s[5]) < 0.01), None)
        if still is not None:
            stops.append(still - onset)
    result = {"trials": trials, "stopped": done, "times_s": times, "scan_period_s": zone.scan_period,
              "p50_s": percentile(times, 50), "p99_s": percentile(times, 99), "max_s": max(times) if times else None,
              "truth_stop_s": stops, "truth_stop_p50_s": percentile(stops, 50),
              "truth_stop_max_s": max(stops) if stops else None}
    log("ground truth standing still after %s s" % ", ".join("%.3f" % t for t in stops))
    log("reaction: %d/%d stopped, times %s" % (done, trials, ", ".join("%.3f" % t for t in times)))
    fig, (ax, axh) = plt.subplots(1, 2, figsize=(8, 2.8))
    if onsets:
        t0 = onsets[0]
        win = [(t - t0, s) for t, s in commands if -0.5 <= t - t0 <= 0.6]
        ax.plot([w[0] for w in win], [w[1] for w in win], color="tab:blue", lw=1, label="HighCmd speed at the A1")
        ax.axvline(0.0, color="tab:red", lw=1, label="scan with intruder")
        ax.set_xlabel("t - scan stamp [s]")
        ax.set_ylabel("commanded speed")
        ax.legend(fontsize=7)
        ax.set_title("first stop", fontsize=9)
    axh.hist([1000 * t for t in times], bins=10, color="tab:blue")
    axh.axvline(1000 * (zone.scan_period + 0.02), color="k", ls="--", lw=1, label="goal: scan period + 20 ms")
    axh.set_xlabel("software reaction [ms]")
    axh.set_title("reaction time (thesis 440 +- 90 ms incl. mechanics)", fontsize=9)
    axh.legend(fontsize=7)
    result["png"] = save(fig, ctx.out, "reaction.png")
    return result


def exp_mount(ctx):
    """mount_zone.py's measurements (test_mount_zone.py) on this stack, with the shipped mounts file.

    The safety stack is mount_zone.py's stack with sim.launch's default mounts (the same launch
    arguments): measured here, first (the robot where the simulator put it), instead of on a
    stack of its own. ``run_all --mount-check`` runs it.
    """
    import mount_zone
    import rospkg

    return mount_zone.measure(os.path.join(rospkg.RosPack().get_path("rbd_description"), "config", "mounts.yaml"))


import avoidance  # noqa: E402  (issue 17: box, wall, visitor)

EXPERIMENTS = {"control": [("step", exp_step), ("rotation", exp_rotation), ("path", exp_path)],
               "safety": [("mount", exp_mount), ("zone", exp_zone), ("boundary", exp_boundary),
                          ("reaction", exp_reaction),
                          ("detect", avoidance.exp_detect), ("stopping", avoidance.exp_stopping),
                          ("box", avoidance.exp_box), ("wall", avoidance.exp_wall),
                          ("visitor", avoidance.exp_visitor)]}


class Context:
    """What the experiments of one stack share."""

    def __init__(self, stack, out, short):
        self.stack = stack
        self.out = out
        self.short = short
        self.truth = None
        self.pos_started = False
        self._zone = None

    def zone(self):
        """The zone prober (created on first use)."""
        if self._zone is None:
            self._zone = Zone()
        return self._zone


def start_stack(kind, out, seed, columns):
    """Start the stack of `kind` (ground truth may take a few seconds more)."""
    stack = RosEnv(log_dir=os.path.join(out, "logs", kind), use_here=True, prefix="rbd-exp-home.")
    if kind == "control":
        stack.launch("rbd_sim", "mock_a1.launch", "seed:=%d" % seed, name="mock_a1")
    else:
        stack.launch("rbd_bringup", "sim.launch", "localization:=false", "rviz:=false", "gui:=false",
                     "seed:=%d" % seed, "lidar_columns:=%d" % columns, "bridge_port:=%d" % free_port(), name="sim")
    return stack


def main():
    """Run the named experiments of one stack; writes OUT/<name>.json."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--stack", choices=sorted(EXPERIMENTS), required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--short", action="store_true", help="the short versions run by make test")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--columns", type=int, default=0, help="OS1-32 columns (default 512 short, 1024 full)")
    ap.add_argument("names", nargs="*", help="experiments (default: all of the stack)")
    args = ap.parse_args()
    known = dict(EXPERIMENTS[args.stack])
    names = args.names or [n for n, _ in EXPERIMENTS[args.stack]]
    unknown = [n for n in names if n not in known]
    if unknown:
        ap.error("unknown experiment(s) for stack %s: %s" % (args.stack, ", ".join(unknown)))
    os.makedirs(args.out, exist_ok=True)
    t_start = time.monotonic()
    columns = args.columns or (512 if args.short else 1024)
    stack = start_stack(args.stack, args.out, args.seed, columns)
    failed = []
    written = set()
    try:
        import rospy

        rospy.init_node("thesis_experiments_%s" % args.stack, anonymous=True, disable_signals=True)
        ctx = Context(stack, args.out, args.short)
        ctx.truth = Truth()
        if not wait_for(lambda: ctx.truth.last() is not None, 60.0):
            raise RuntimeError("no ground truth from the simulator")
        log("%s stack up in %.1f s" % (args.stack, time.monotonic() - t_start))
        for name in names:
            t0 = time.monotonic()
            try:
                result = known[name](ctx)
            except Exception as exc:  # one failed experiment must not hide the others
                log("%s FAILED: %s" % (name, exc))
                result = {"error": str(exc)}
                failed.append(name)
            result["short"] = args.short
            result["seconds"] = time.monotonic() - t0
            with open(os.path.join(args.out, name + ".json"), "w") as fh:
                json.dump(result, fh, indent=2, sort_keys=True)
            written.add(name)
            log("%s done in %.1f s" % (name, result["seconds"]))
            if "error" not in result:  # the result next to the thesis value
                print(thesis.render_table(thesis.rows({name: result})), flush=True)
    except Exception as exc:  # the stack itself failed: every experiment not run says why
        log("%s stack FAILED: %s\n%s" % (args.stack, exc, stack.tails(40)))
        for name in names:
            if name not in written:
                with open(os.path.join(args.out, name + ".json"), "w") as fh:
                    json.dump({"error": "%s stack: %s" % (args.stack, exc), "short": args.short}, fh)
                failed.append(name)
    finally:
        stack.close(timeout=25.0)  # roslaunch itself escalates SIGINT -> SIGTERM after 15 s
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
