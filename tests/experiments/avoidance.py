"""Issue 17 experiments (active collision avoidance) on the safety stack, measured on ground truth.

- ``box``: during ``walk`` a 0.4 m box is dropped with its near face 0.5 m ahead of the walking
  robot's footprint (outside its stop zone, as a visitor drops a bag; on the way back, where the
  detour has room). Measured per trick pose: reached within
  0.1 m or skipped with the controller's reason; time lost against the same trick without a box;
  minimum footprint-box clearance; contacts. Then the same with ``~avoidance`` off: the robot
  must still be standing, trick pending, after the "blocked forever" time (thesis behaviour).
- ``wall``: a wall panel with its face 0.45 m ahead of the idle robot, then ``walk``: it escapes,
  takes the gesture and completes the trick or skips poses with a reason; the same with
  avoidance off ends blocked.
- ``visitor``: with ``~dodge`` on, a person walks straight at the idle robot at 0.5 and 1.0 m/s,
  stops 0.55 m from its home (centre), waits, leaves. Measured: the robot steps back (largest
  offset from home, bounded by ``~dodge_max``), never leaves the arena, returns home; minimum
  clearance; contacts.

Everything safety-related comes from the simulator: ``/rbd_sim/ground_truth`` (footprint vs box
rectangle / person cylinder, rbd_bringup.metrics), the world's obstacle markers, and the arena
the controller publishes. The controller's own topics only label what happened (states,
avoidance events, the detour for the figure).
"""

import math
import threading
import time

import analysis  # tests/experiments is on the path (experiments.py runs these)

from rbd_geometry.rotation import yaw_of, yaw_to_quat  # noqa: E402
from rbd_testkit import wait_for

HERE_NOTE = "issue 17"
BOX = 0.4  # edge of the box [m]
#: The box lands this far ahead of the robot's footprint [m]: outside the stop zone (0.37 m ahead of it).
DROP_GAP = 0.5


def log(msg):
    """One progress line."""
    print("[avoidance] %s" % msg, flush=True)


class Watch:
    """Ground truth, controller states, avoidance events, detour plans, queue and arena."""

    def __init__(self):
        import rospy
        from geometry_msgs.msg import PolygonStamped
        from nav_msgs.msg import Odometry, Path
        from std_msgs.msg import String

        from rbd_msgs.msg import PathQueue

        self.lock = threading.Lock()
        self.truth = []  # (t, x, y, yaw, speed, vx, vy): velocity in the world frame
        self.states = []  # (t, state)
        self.state = ""
        self.events = []  # (t, text)
        self.plans = []  # (t, [(x, y)])
        self.queue = []
        self.arena = None
        self.subs = [
            rospy.Subscriber("/rbd_sim/ground_truth", Odometry, self._on_truth, queue_size=200),
            rospy.Subscriber("/rbd_controller/state", String, self._on_state, queue_size=50),
            rospy.Subscriber("/rbd_controller/avoidance", String, self._on_event, queue_size=50),
            rospy.Subscriber("/rbd_controller/detour", Path, self._on_plan, queue_size=5),
            rospy.Subscriber("/rbd_controller/path_queue", PathQueue, self._on_queue, queue_size=5),
            rospy.Subscriber("/rbd_controller/arena", PolygonStamped, self._on_arena, queue_size=1),
        ]
        # A new subscriber connects after a while under load; every experiment reads pose() and
        # state at once (a CI run at load 18 crashed on a pose() of None).
        self.zone_model = lidar_zone_model()
        if not wait_for(lambda: self.truth and self.state, 30.0):
            self.close()
            raise RuntimeError("no ground truth or controller state within 30 s (truth %d samples, state %r)"
                               % (len(self.truth), self.state))

    def _on_truth(self, msg):
        p, q, tw = msg.pose.pose.position, msg.pose.pose.orientation, msg.twist.twist.linear
        yaw = yaw_of(q)
        c, s = math.cos(yaw), math.sin(yaw)  # the twist is in the body frame
        with self.lock:
            self.truth.append((time.monotonic(), p.x, p.y, yaw, math.hypot(tw.x, tw.y), c * tw.x - s * tw.y,
                               s * tw.x + c * tw.y))
            if len(self.truth) > 60000:
                del self.truth[:20000]

    def _on_state(self, msg):
        with self.lock:
            self.state = msg.data
            self.states.append((time.monotonic(), msg.data))

    def _on_event(self, msg):
        with self.lock:
            self.events.append((time.monotonic(), msg.data))
        log("controller: %s" % msg.data)

    def _on_plan(self, msg):
        with self.lock:
            self.plans.append((time.monotonic(), [(p.pose.position.x, p.pose.position.y) for p in msg.poses]))

    def _on_queue(self, msg):
        with self.lock:
            self.queue = [(p.position.x, p.position.y) for p in msg.poses]

    def _on_arena(self, msg):
        with self.lock:
            self.arena = [(p.x, p.y) for p in msg.polygon.points]

    def pose(self):
        """Latest ground truth (x, y, yaw)."""
        with self.lock:
            return self.truth[-1][1:4] if self.truth else None

    def since(self, t0):
        """Ground-truth samples after t0 (monotonic)."""
        with self.lock:
            return [s for s in self.truth if s[0] >= t0]

    def wait_state(self, states, timeout):
        """Until the controller is in one of states."""
        return wait_for(lambda: self.state in states, timeout)

    def close(self):
        """Unsubscribe."""
        for s in self.subs:
            s.unregister()


class Operator:
    """Releases the e-stop, shows gestures (on the topic the bridge feeds), switches parameters."""

    def __init__(self, watch):
        import rospy
        from std_msgs.msg import String
        from std_srvs.srv import SetBool

        from rbd_msgs.srv import PlaceBox, PlaceObstacle

        self.watch = watch
        self.gesture_pub = rospy.Publisher("/rbd_gestrec/gesture", String, queue_size=1)
        rospy.wait_for_service("/rbd_controller/em_stop", 60.0)
        self.em_stop = rospy.ServiceProxy("/rbd_controller/em_stop", SetBool)
        self.place_box = rospy.ServiceProxy("/rbd_sim/place_box", PlaceBox)
        self.place_cylinder = rospy.ServiceProxy("/rbd_sim/place_obstacle", PlaceObstacle)
        self.String = String

    def goto(self, x, y, yaw, rehome=True):
        """Walk the waiting robot to a world pose (the position controller directly); home is there then."""
        import rospy
        from geometry_msgs.msg import Pose

        from rbd_msgs.srv import SetPosition

        goal = Pose()
        goal.position.x, goal.position.y = x, y
        _x, _y, goal.orientation.z, goal.orientation.w = yaw_to_quat(yaw)
        rospy.ServiceProxy("/rbd_pos_controller/set_position", SetPosition)(pose=goal)

        def there():
            px, py, pyaw = self.watch.pose()
            return math.hypot(px - x, py - y) < 0.05 and abs(math.sin((pyaw - yaw) / 2.0)) < 0.03

        wait_for(there, 40.0)
        time.sleep(1.0)
        if rehome and self.watch.state == "WAITING_FOR_GESTURE":
            # Like an operator who puts the robot somewhere new: e-stop, release there = its new home.
            self.em_stop(True)
            self.watch.wait_state(("EMERGENCY_STOP",), 5.0)
            self.release()

    def release(self):
        """E-stop off, waiting for gestures."""
        if self.watch.state != "WAITING_FOR_GESTURE":
            self.em_stop(False)
        return self.watch.wait_state(("WAITING_FOR_GESTURE",), 30.0)

    def gesture(self, command, until=("GENERATING_PATH", "EXECUTING"), timeout=60.0):
        """Show the gesture every 0.5 s until the controller takes it."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.watch.state in until:
                return True
            if self.watch.state == "WAITING_FOR_GESTURE":
                self.gesture_pub.publish(self.String(command))
            time.sleep(0.5)
        return False

    @staticmethod
    def switch(name, value):
        """Set an rbd_controller parameter (re-read within 1 s)."""
        import rospy

        rospy.set_param("/rbd_controller/%s" % name, value)
        time.sleep(1.3)


def footprint_trace(samples, boxes, people=None):
    """Minimum clearance and contacts along ground-truth samples (rbd_bringup.metrics)."""
    from rbd_bringup.metrics import footprint_box_clearance, footprint_clearance

    best, contacts = math.inf, 0
    touching = False
    for s in samples:
        t, x, y, yaw = s[0], s[1], s[2], s[3]
        d = math.inf
        for bx, by, byaw, sx, sy in boxes:
            d = min(d, footprint_box_clearance((x, y), yaw, (bx, by), byaw, (sx, sy)))
        for px, py, r in (people(t) if people else []):
            d = min(d, footprint_clearance((x, y), yaw, (px, py), r))
        best = min(best, d)
        if d <= 0.0 and not touching:
            contacts += 1
        touching = d <= 0.0
    return best, contacts


def lidar_zone_model():
    """rbd_lidar's rest zone, growth parameters and zone origin in base_link: to draw the zone it swept."""
    import rospy
    import tf2_ros

    from rbd_controller.footprint import ZoneGrowth

    ns = "/rbd_lidar"
    zone = tuple(float(rospy.get_param(ns + "/zone_" + side, d)) for side, d in (
        ("front", 0.70), ("left", 0.35), ("back", 0.55), ("right", 0.35)))
    d = ZoneGrowth()
    growth = ZoneGrowth(reaction_time=float(rospy.get_param(ns + "/reaction_time", d.reaction_time)),
                        rotation_lever=float(rospy.get_param(ns + "/rotation_lever", d.rotation_lever)),
                        max_growth=float(rospy.get_param(ns + "/max_growth", d.max_growth)),
                        enabled=bool(rospy.get_param(ns + "/velocity_aware", d.enabled)))
    origin = (0.0, 0.0)
    frame = str(rospy.get_param(ns + "/zone_frame", ""))
    if frame:
        buf = tf2_ros.Buffer()
        listener = tf2_ros.TransformListener(buf)  # noqa: F841 - fills buf
        try:
            tr = buf.lookup_transform("base_link", frame, rospy.Time(0), rospy.Duration(5.0)).transform.translation
            origin = (tr.x, tr.y)
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException) as err:
            log("zone frame %s not in TF (%s): zone drawn from base_link" % (frame, err))
    return zone, growth, origin


def swept_zones(samples, states, model, every=0.5):
    """The stop zone rbd_lidar checked while AVOIDING, at ground-truth poses every ``every`` s.

    Each rectangle is the rest zone grown (rbd_controller.footprint, rbd_lidar's rule) for the
    ground-truth speed and yaw rate there; corners in the world frame.
    """
    from rbd_controller.footprint import grown_zone

    zone, growth, (ox, oy) = model
    spans, since = [], None
    for t, st in states:
        if st == "AVOIDING" and since is None:
            since = t
        elif st != "AVOIDING" and since is not None:
            spans.append((since, t))
            since = None
    if since is not None:
        spans.append((since, math.inf))
    out, last = [], -math.inf
    for a, b in zip(samples, samples[1:]):
        t = a[0]
        if t - last < every or not any(t0 <= t <= t1 for t0, t1 in spans):
            continue
        last = t
        dt = max(b[0] - a[0], 1e-3)
        wz = math.atan2(math.sin(b[3] - a[3]), math.cos(b[3] - a[3])) / dt
        f, left, back, right = grown_zone(zone, a[4], 0.0, wz, growth)
        c, s = math.cos(a[3]), math.sin(a[3])
        corners = [(ox + f, oy + left), (ox - back, oy + left), (ox - back, oy - right), (ox + f, oy - right)]
        out.append([(round(a[1] + c * u - s * v, 3), round(a[2] + s * u + c * v, 3)) for u, v in corners])
    return out


def stationary_for(samples, radius=0.05):
    """Seconds the robot has stayed within radius of where it is at the end of samples."""
    if not samples:
        return 0.0
    _, x, y = samples[-1][:3]
    t_end = samples[-1][0]
    for s in reversed(samples):
        if math.hypot(s[1] - x, s[2] - y) > radius:
            return t_end - s[0]
    return t_end - samples[0][0]


def trick_poses(start, names=("walk forward 0.6 m", "walk back to -0.6 m", "return to start")):
    """The walk trick's three goals from its start pose (rbd_navigation's tricks.yaml)."""
    x, y, yaw = start
    c, s = math.cos(yaw), math.sin(yaw)
    return [(names[0], x + 0.6 * c, y + 0.6 * s), (names[1], x - 0.6 * c, y - 0.6 * s), (names[2], x, y)]


def pose_outcomes(samples, goals, events):
    """Per goal: closest approach and whether the controller reported skipping it."""
    skipped = [e for _, e in events if e.startswith("gave_up")]
    out = []
    for name, gx, gy in goals:
        closest = min((math.hypot(s[1] - gx, s[2] - gy) for s in samples), default=math.inf)
        out.append({"pose": name, "goal": [round(gx, 3), round(gy, 3)], "closest_m": round(closest, 3),
                    "reached": closest <= 0.1})
    return out, skipped


def run_trick_with_box(ctx, watch, op, trick, avoidance, blocked_wait):
    """One trick with a box dropped 0.5 m ahead of the walking robot; returns the measurements.

    ``walk`` gets it on its way back (between its poses: at least one pose then has the box in
    its stop zone and is skipped with a reason); ``stroll`` on its way out, 0.1 m past the start,
    so that there is room for a detour: the box's far side (0.1 + 0.25 + 0.5 + 0.4 = 1.25 m along)
    stays out of the stop zone of the stroll's far pose (2 m along; the zone reaches 0.55 m behind
    its frame, which is 0.08 m behind base_link: 1.37 m along). Dropped later (0.3 m, as before
    round 3), the far pose's zone holds the box and the pose is skipped instead of reached.
    """
    import rospy

    from rbd_bringup.metrics import box_ahead

    op.switch("avoidance", avoidance)
    op.release()
    # The lab's free middle: its people walk at x > 2.8 m and y < -2 m, furniture stands at
    # x < -2 m; from (1, 0) facing -x the stroll's far pose (-1, 0) keeps 1.5 m from all of it.
    op.goto(1.0, 0.0, math.pi)
    start = watch.pose()
    t0 = time.monotonic()
    if not op.gesture(trick):
        raise RuntimeError("%s not taken" % trick)
    if trick == "walk":  # the way back: heading turned to the start's back, past the first pose
        ok = wait_for(lambda: _walking(watch, start, back=True), 40.0, 0.02)
    else:  # the way out, 0.1 m past the start
        ok = wait_for(lambda: _walking(watch, start, back=False), 40.0, 0.02)
    if not ok:
        raise RuntimeError("the robot never walked where the box goes")
    x, y, yaw = watch.pose()
    # As a visitor drops a bag: its face DROP_GAP ahead of the footprint, outside the stop zone.
    bx, by, byaw = box_ahead((x, y, yaw), DROP_GAP, (BOX, BOX))
    op.place_box(name="bag", x=bx, y=by, yaw=byaw, size_x=BOX, size_y=BOX, height=BOX, remove=False)
    t_box = time.monotonic()
    log("box dropped at (%.2f, %.2f), face %.2f m ahead of the footprint of the robot at (%.2f, %.2f) (avoidance %s)"
        % (bx, by, DROP_GAP, x, y, "on" if avoidance else "off"))
    result = {"trick": trick, "avoidance": avoidance, "box": [bx, by, byaw, BOX, BOX], "robot_at_drop": [x, y, yaw],
              "drop_gap_m": DROP_GAP}
    if avoidance:
        # Up to 5 min: a stroll round the bag has taken 116-154 s of stop-and-go (the zone shrinks
        # when the robot stops, clears, and grows again when it resumes) before it is BLOCKED; the
        # experiment reports that time lost rather than cutting the trick short.
        done = watch.wait_state(("WAITING_FOR_GESTURE",), 300.0)
        t1 = time.monotonic()
        result["completed"] = done
        result["duration_s"] = t1 - t0
    else:
        watch.wait_state(("COLLISION_DETECTED", "BLOCKED"), 5.0)
        time.sleep(blocked_wait)
        samples = watch.since(t_box)
        result["stationary_s"] = stationary_for(samples)
        with watch.lock:
            result["state_at_end"] = watch.state
            result["trick_pending"] = bool(watch.queue)
        result["blocked_forever"] = (result["stationary_s"] >= blocked_wait - 1.0 and result["trick_pending"]
                                     and result["state_at_end"] in ("BLOCKED", "COLLISION_DETECTED"))
        t1 = time.monotonic()
    samples = watch.since(t0)
    result["min_clearance_m"], result["contacts"] = footprint_trace(watch.since(t_box), [result["box"]])
    with watch.lock:
        events = [(t, e) for t, e in watch.events if t >= t0]
        plans = [p for t, p in watch.plans if t >= t0]
        states = [s for t, s in watch.states if t0 <= t <= t1]
        arena = watch.arena
    goals = trick_poses(start) if trick == "walk" else stroll_poses(start)
    result["poses"], result["skipped"] = pose_outcomes(samples, goals, events)
    result["obstacles_avoided"] = sum(1 for _, e in events if e.startswith("avoided"))
    result["events"] = [e for _, e in events]
    result["states"] = states
    # When (s after the gesture): where the time went (classification, escape, plans, detour, way back).
    with watch.lock:
        result["timeline"] = [(round(t - t0, 2), st) for t, st in watch.states if t0 <= t <= t1] + [
            (round(t - t0, 2), e[:60]) for t, e in events]
    result["timeline"].sort()
    result["box_dropped_s"] = round(t_box - t0, 2)
    result["track"] = [[round(v, 3) for v in smp[:5]] for smp in samples[::10]]  # t (absolute), x, y, yaw, speed
    result["t0"] = t0
    result["path"] = [(s[1], s[2]) for s in samples[::5]]
    result["plans"] = plans
    result["arena"] = arena
    if avoidance:
        planned = [t for t, e in events if e.startswith("plan:")]
        # Collision stops once the first detour was planned (issue 27: none), and which planner ran.
        result["stops_after_plan"] = sum(1 for (t, st), (_, prev) in zip(watch.states[1:], watch.states)
                                         if planned and t0 <= t <= t1 and t > planned[0]
                                         and st == "COLLISION_DETECTED" and prev != st)
        result["planners"] = [e.split(":", 2)[1].split(",")[0].strip() for _, e in events if e.startswith("plan:")]
        with watch.lock:
            states_t = [(t, st) for t, st in watch.states if t0 <= t <= t1]
        result["swept"] = swept_zones(samples, states_t, watch.zone_model)
    op.place_box(name="bag", remove=True)
    if not avoidance:
        op.switch("avoidance", True)  # let the pending trick finish, clear of the box
        watch.wait_state(("WAITING_FOR_GESTURE",), 60.0)
    rospy.sleep(0.5)
    return result


def stroll_poses(start):
    """The stroll trick's goals (rbd_navigation's tricks.yaml): 2 m out, back, turned forward."""
    x, y, yaw = start
    return [("stroll forward 2 m", x + 2.0 * math.cos(yaw), y + 2.0 * math.sin(yaw)),
            ("stroll back to the start", x, y), ("face forward again", x, y)]


def _walking(watch, start, back):
    """Walking (> 0.15 m/s, EXECUTING) away from start (back=False: heading as at the start, 0.1 m
    past it) or back towards it (heading turned round, not yet 0.45 m past the start)."""
    with watch.lock:
        if len(watch.truth) < 2 or watch.state != "EXECUTING":
            return False
        _, x, y, yaw, speed = watch.truth[-1][:5]
    sx, sy, syaw = start
    along = (x - sx) * math.cos(syaw) + (y - sy) * math.sin(syaw)
    if back:
        return math.cos(yaw - syaw) < -0.95 and speed > 0.15 and along < 0.45
    return math.cos(yaw - syaw) > 0.95 and speed > 0.15 and along > 0.1


def baseline(watch, op, trick):
    """Duration of the trick without a box [s]."""
    op.release()
    t0 = time.monotonic()
    op.gesture(trick)
    watch.wait_state(("WAITING_FOR_GESTURE",), 90.0)
    return time.monotonic() - t0


def exp_box(ctx):
    """A 0.4 m box 0.5 m ahead of the walking robot: walk (skips), stroll (detour), and avoidance off."""
    watch = Watch()
    op = Operator(watch)
    result = {"blocked_forever_s": 15.0 if ctx.short else 60.0}
    try:
        for trick in (("stroll",) if ctx.short else ("stroll", "walk")):
            on = run_trick_with_box(ctx, watch, op, trick, True, 0.0)
            on["baseline_s"] = None if ctx.short else baseline(watch, op, trick)
            on["time_lost_s"] = None if on["baseline_s"] is None else on["duration_s"] - on["baseline_s"]
            result[trick] = on
            log("box in %s (avoidance on): completed %s in %.1f s (lost %s s), min clearance %.3f m, contacts %d, "
                "avoided %d, poses %s, skipped %s, planners %s, collision stops after the plan %d" % (
                    trick, on["completed"], on["duration_s"], on["time_lost_s"], on["min_clearance_m"],
                    on["contacts"], on["obstacles_avoided"], [(p["pose"], p["closest_m"]) for p in on["poses"]],
                    on["skipped"], on["planners"], on["stops_after_plan"]))
        off = run_trick_with_box(ctx, watch, op, "walk", False, result["blocked_forever_s"])
        result["off"] = off
        log("box in walk (avoidance off): stationary %.1f s in %s, trick pending %s" % (
            off["stationary_s"], off["state_at_end"], off["trick_pending"]))
    finally:
        watch.close()
    panels = [result[t] for t in ("stroll", "walk") if t in result] + [result["off"]]
    result["png"] = plot(ctx, "avoid_box.png", "0.4 m box 0.5 m ahead", panels)
    return result


def exp_detect(ctx):
    """The lowest box the zone sees, per side, just inside the zone's edge and 5 cm from the footprint.

    The OS1 sits 0.35 m above the floor and its lowest beam points 21.5 deg down, and rbd_lidar
    ignores the floor band (``floor_clearance``): close to the robot only taller things reach a
    beam. A 0.4 m wide, 0.2 m deep box faces each side at the two distances; its height is bisected
    (1 cm) for the lowest that makes ``point_threshold`` critical points in the second scan after it
    is placed. The robot stands in EMERGENCY_STOP meanwhile (no avoidance motion).
    """
    import rospy
    from std_srvs.srv import SetBool

    from rbd_bringup.metrics import A1_FOOTPRINT_LENGTH, A1_FOOTPRINT_WIDTH
    from rbd_msgs.srv import PlaceBox

    zone = ctx.zone()
    watch = Watch()
    place = rospy.ServiceProxy("/rbd_sim/place_box", PlaceBox)
    # Run first on a fresh stack (``--only detect``), the controller may not be up yet.
    rospy.wait_for_service("/rbd_controller/em_stop", 60.0)
    rospy.ServiceProxy("/rbd_controller/em_stop", SetBool)(True)
    try:
        if not wait_for(lambda: watch.pose() is not None and watch.state == "EMERGENCY_STOP", 10.0):
            raise RuntimeError("no ground truth or not in EMERGENCY_STOP")
        # Earlier experiments walk the robot (reaction, box, ...): wait until it stands, then read
        # where the LiDAR is now. The prober's pose from its creation would put every box off by
        # how far the robot moved since (0.12 m ahead after the reaction trials: the back boxes
        # landed outside the back zone).
        if not wait_for(lambda: watch.pose() is not None and watch.truth[-1][4] < 0.005, 10.0):
            raise RuntimeError("the robot does not stand still in EMERGENCY_STOP")
        zone.locate()
        x, y, yaw = watch.pose()
        # The LiDAR in the body frame: where the footprint's edges are, seen from it.
        dx, dy = zone.origin[0] - x, zone.origin[1] - y
        lx = math.cos(yaw) * dx + math.sin(yaw) * dy
        ly = -math.sin(yaw) * dx + math.cos(yaw) * dy
        mount = zone.mount("base_link")
        if math.hypot(lx - mount[0], ly - mount[1]) > 0.01:
            raise RuntimeError("LiDAR at (%.3f, %.3f) m in the body on ground truth, mounted at (%.3f, %.3f) m"
                               % (lx, ly, mount[0], mount[1]))
        half_l, half_w = A1_FOOTPRINT_LENGTH / 2.0, A1_FOOTPRINT_WIDTH / 2.0
        # (name, angle from the LiDAR, rbd_msgs/CollisionState side index, zone limit, footprint edge)
        sides = [("front", 0.0, 0, zone.zone[0], half_l - lx), ("back", math.pi, 2, zone.zone[1], half_l + lx),
                 ("left", math.pi / 2, 1, zone.zone[2], half_w - ly), ("right", -math.pi / 2, 3, zone.zone[3],
                                                                      half_w + ly)]
        threshold = zone.threshold

        def seen(angle, dist, height):
            a = zone.yaw + angle
            cx, cy = zone.origin[0] + (dist + 0.1) * math.cos(a), zone.origin[1] + (dist + 0.1) * math.sin(a)
            if not place(name="probe", x=cx, y=cy, yaw=a, size_x=0.2, size_y=0.4, height=height,
                         remove=False).success:
                raise RuntimeError("place_box refused")
            return zone.tripped(rospy.get_time())

        out = []
        for name, angle, _index, limit, edge in sides:
            row = {"side": name, "zone_m": limit, "footprint_edge_m": round(edge, 3)}
            for key, dist in (("zone_edge", limit - 0.03), ("footprint", edge + 0.05)):
                h = analysis.lowest_true(lambda hh, a=angle, d=dist: seen(a, d, hh), 0.01, 0.8, 0.01)
                row[key + "_dist_m"] = round(dist, 3)
                row[key + "_min_height_m"] = None if h is None else round(h, 3)
            out.append(row)
            log("lowest box seen on the %s: %s m just inside the zone (%.2f m from the LiDAR), %s m 5 cm from the "
                "footprint (%.2f m)" % (name, row["zone_edge_min_height_m"], row["zone_edge_dist_m"],
                                        row["footprint_min_height_m"], row["footprint_dist_m"]))
        place(name="probe", remove=True)
        x1, y1, _ = watch.pose()
        if math.hypot(x1 - x, y1 - y) > 0.01:
            raise RuntimeError("the robot moved %.3f m while the boxes were probed" % math.hypot(x1 - x, y1 - y))
        return {"threshold": threshold, "sides": out, "lidar_in_body_m": [round(lx, 4), round(ly, 4)],
                "floor_clearance_m": float(rospy.get_param("/rbd_lidar/floor_clearance", 0.1))}
    finally:
        watch.close()


def exp_stopping(ctx):
    """How close to the walking robot a box may land and still be stopped for: the stopping distance.

    The robot walks at full speed towards a goal 2.2 m away (position controller, e-stop released,
    avoidance off so that it stays where it stopped); a 0.4 m box lands ``gap`` ahead of its
    footprint; measured on ground truth: the clearance left when it stands, so the distance it
    needed to stop (gap - clearance) and whether it touched the box. A box landing closer than that
    distance cannot be avoided by any controller; the demo, the soak and the box experiment drop
    theirs 0.5 m ahead (outside the stop zone, which reaches 0.37 m ahead of the footprint).
    """
    import rospy
    from geometry_msgs.msg import Pose

    from rbd_bringup.metrics import box_ahead
    from rbd_msgs.srv import SetPosition

    watch = Watch()
    op = Operator(watch)
    set_position = rospy.ServiceProxy("/rbd_pos_controller/set_position", SetPosition)
    out = {"runs": []}
    try:
        op.switch("avoidance", False)
        op.release()
        for gap in (0.3, 0.2, 0.15, 0.1, 0.05):
            op.goto(1.0, 0.0, math.pi)
            goal = Pose()
            goal.position.x = -1.2
            goal.orientation.z, goal.orientation.w = 1.0, 0.0
            set_position(pose=goal)
            if not wait_for(lambda: _speed(watch) >= 0.25, 10.0, 0.01):
                raise RuntimeError("the robot never reached walking speed")
            x, y, yaw = watch.pose()
            speed = _speed(watch)
            bx, by, byaw = box_ahead((x, y, yaw), gap, (BOX, BOX))
            op.place_box(name="stop_box", x=bx, y=by, yaw=byaw, size_x=BOX, size_y=BOX, height=BOX, remove=False)
            t_drop = time.monotonic()
            time.sleep(3.0)
            clearance, contacts = footprint_trace(watch.since(t_drop), [(bx, by, byaw, BOX, BOX)])
            run = {"gap_m": gap, "speed_mps": round(speed, 3), "clearance_m": round(clearance, 3),
                   "stopping_distance_m": round(gap - max(clearance, 0.0), 3), "contacts": contacts}
            out["runs"].append(run)
            log("box %.2f m ahead of the footprint at %.2f m/s: stopped with %.3f m left (stopping distance %.3f m), "
                "contacts %d" % (gap, speed, clearance, run["stopping_distance_m"], contacts))
            op.place_box(name="stop_box", remove=True)
            watch.wait_state(("WAITING_FOR_GESTURE",), 10.0)
        op.switch("avoidance", True)
    finally:
        watch.close()
    safe = [r["gap_m"] for r in out["runs"] if r["contacts"] == 0]
    out["smallest_gap_without_contact_m"] = min(safe) if safe else None
    out["max_stopping_distance_m"] = max(r["stopping_distance_m"] for r in out["runs"] if r["contacts"] == 0) \
        if safe else None
    return out


def exp_wall(ctx):
    """A wall 0.45 m ahead of the idle robot, then walk; with and without avoidance."""
    import rospy

    watch = Watch()
    op = Operator(watch)
    runs = {}
    try:
        for avoidance in (True, False):
            op.switch("avoidance", avoidance)
            op.release()
            wait_for(lambda: watch.state == "WAITING_FOR_GESTURE", 30.0)
            start = watch.pose()
            x, y, yaw = start
            d = 0.45 + 0.05  # the panel is 0.1 m thick: its face 0.45 m ahead of base_link
            wx, wy = x + d * math.cos(yaw), y + d * math.sin(yaw)
            wall = [wx, wy, yaw, 0.1, 3.0]
            op.place_box(name="wall", x=wx, y=wy, yaw=yaw, size_x=0.1, size_y=3.0, height=1.2, remove=False)
            t0 = time.monotonic()
            log("wall panel 0.45 m ahead of the robot at (%.2f, %.2f) (avoidance %s)" % (
                x, y, "on" if avoidance else "off"))
            r = {"avoidance": avoidance, "wall": wall, "start": list(start)}
            # The zone sees the wall; with avoidance the idle robot steps back, then takes gestures.
            watch.wait_state(("COLLISION_DETECTED", "BLOCKED"), 5.0)
            if avoidance:
                r["escaped"] = wait_for(lambda: watch.state == "WAITING_FOR_GESTURE", 40.0)
                r["taken"] = op.gesture("walk", timeout=60.0)
                r["completed"] = r["taken"] and watch.wait_state(("WAITING_FOR_GESTURE",), 120.0)
                r["duration_s"] = time.monotonic() - t0
            else:
                wait = 15.0 if ctx.short else 60.0
                r["taken"] = op.gesture("walk", timeout=wait)
                samples = watch.since(t0)
                r["stationary_s"] = stationary_for(samples)
                r["state_at_end"] = watch.state
                r["blocked_forever"] = not r["taken"] and r["stationary_s"] >= wait - 1.0
            t1 = time.monotonic()
            samples = watch.since(t0)
            r["min_clearance_m"], r["contacts"] = footprint_trace(samples, [wall])
            with watch.lock:
                events = [(t, e) for t, e in watch.events if t >= t0]
                r["plans"] = [p for t, p in watch.plans if t >= t0]
                r["states"] = [s for t, s in watch.states if t0 <= t <= t1]
                r["arena"] = watch.arena
            r["events"] = [e for _, e in events]
            r["skipped"] = [e for _, e in events if e.startswith("gave_up")]
            r["path"] = [(s[1], s[2]) for s in samples[::5]]
            op.place_box(name="wall", remove=True)
            runs["on" if avoidance else "off"] = r
            log("wall (avoidance %s): %s" % ("on" if avoidance else "off", {
                k: r[k] for k in ("completed", "stationary_s", "blocked_forever", "min_clearance_m", "contacts",
                                  "skipped") if k in r}))
        op.switch("avoidance", True)
        watch.wait_state(("WAITING_FOR_GESTURE",), 30.0)
        rospy.sleep(0.5)
    finally:
        watch.close()
    runs["png"] = plot(ctx, "avoid_wall.png", "Wall 0.45 m ahead, then walk", [runs["on"], runs["off"]])
    return runs


def exp_visitor(ctx):
    """Visitors walk at the idle robot: one at 0.5 and 1.0 m/s, then two (ahead, then behind it).

    Short form (make test): the two-visitor run only.
    """
    import rospy

    watch = Watch()
    op = Operator(watch)
    out = {"runs": []}
    try:
        # From the lab's free middle, re-homed there like an operator would (e-stop, release): the
        # experiments before this one may leave the robot anywhere (after the wall it skips walking
        # home), and with the dodge on it would walk back to its old home into the visitor's path.
        op.release()
        op.goto(1.0, 0.0, math.pi)
        op.switch("dodge", True)
        dodge_max = float(rospy.get_param("/rbd_controller/dodge_max", 0.5))
        runs = [(1.0, True)] if ctx.short else [(0.5, False), (1.0, False), (1.0, True)]
        for v, second in runs:
            out["runs"].append(visitor_run(watch, op, v, dodge_max, second))
        op.switch("dodge", False)
    finally:
        watch.close()
    out["png"] = plot_visitor(ctx, out["runs"])
    return out


class Visitors:
    """Scripted visitors (cylinders through /rbd_sim/place_obstacle) on the home pose's axis, 20 Hz.

    Positions are distances along the robot's heading at home (> 0 ahead, < 0 behind); every
    update is recorded with each visitor's velocity, for contacts and for "never towards".
    """

    RADIUS = 0.22

    def __init__(self, op, home):
        self.op = op
        self.home = home
        self.at = {}  # name -> distance along the axis [m]
        self.track = []  # (t, [(name, x, y, radius, vx, vy)])

    def _xy(self, d):
        x, y, yaw = self.home
        return x + d * math.cos(yaw), y + d * math.sin(yaw)

    def _record(self, velocity):
        t = time.monotonic()
        c, s = math.cos(self.home[2]), math.sin(self.home[2])
        people = []
        for name, d in self.at.items():
            x, y = self._xy(d)
            v = velocity.get(name, 0.0)
            people.append((name, x, y, self.RADIUS, v * c, v * s))
        self.track.append((t, people))

    def move(self, moves, speed):
        """Walk each (name, from, to) at speed [m/s], together; blocks until all arrived."""
        n = max(1, int(max(abs(b - a) for _, a, b in moves) / speed * 20))
        velocity = {name: math.copysign(speed, b - a) for name, a, b in moves}
        for i in range(n + 1):
            for name, a, b in moves:
                self.at[name] = a + (b - a) * i / n
                x, y = self._xy(self.at[name])
                self.op.place_cylinder(name=name, x=x, y=y, radius=self.RADIUS, height=1.7, remove=False)
            self._record(velocity if i < n else {})
            time.sleep(0.05)

    def stand(self, seconds):
        """Everybody stands still for seconds."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self._record({})
            time.sleep(0.05)

    def leave(self):
        """Take every visitor away."""
        for name in list(self.at):
            self.op.place_cylinder(name=name, remove=True)
        self.at = {}
        self._record({})

    def people(self, t):
        """The visitors at time t (nearest record within 0.2 s)."""
        if not self.track:
            return []
        best = min(self.track, key=lambda r: abs(r[0] - t))
        return best[1] if abs(best[0] - t) < 0.2 else []


def visitor_run(watch, op, v, dodge_max, second=False):
    """One approach at v [m/s]: a visitor walks in from 2.2 m to 0.55 m, stands 3 s and leaves.

    With ``second``, a second visitor walks at the robot from behind at 0.8 m/s as soon as it steps
    back from the first (DODGING, moving), up to 1.3 m behind home, then at 0.25 m/s up to 0.2 m
    behind the robot's footprint: the robot must not back into them (``never towards a moving
    person``, on ground truth).
    """
    from rbd_bringup.metrics import A1_FOOTPRINT_LENGTH, TowardsMonitor, footprint_clearance, outside_polygon

    watch.wait_state(("WAITING_FOR_GESTURE",), 30.0)
    time.sleep(1.0)
    home = watch.pose()
    x, y, yaw = home
    crowd = Visitors(op, home)
    t0 = time.monotonic()
    crowd.move([("visitor", 2.2, 0.55)], v)
    second_started = None
    if second:
        moving_back = wait_for(lambda: watch.state == "DODGING" and _speed(watch) > 0.05, 5.0, 0.02)
        second_started = watch.state if moving_back else None
        crowd.move([("visitor2", -2.0, -1.3)], 0.8)
        # Then slowly on to 0.2 m behind the robot's footprint (as it is now): still walking when it
        # is within TowardsMonitor's band (0.5 m) well past its reaction grace, so the rule "never
        # towards a moving person" is exercised, not only passed by a visitor who stopped short of
        # the band (at -1.1 m the band was never held long enough at low load: 0 samples).
        rx, ry, _ = watch.pose()
        rear = (rx - x) * math.cos(yaw) + (ry - y) * math.sin(yaw) - A1_FOOTPRINT_LENGTH / 2.0
        crowd.move([("visitor2", -1.3, max(-1.3, rear - Visitors.RADIUS - 0.2))], 0.25)
    crowd.stand(3.0)
    crowd.move([(n, d, math.copysign(3.0, d)) for n, d in crowd.at.items()], v)
    crowd.leave()
    back = wait_for(lambda: watch.state == "WAITING_FOR_GESTURE" and _near(watch.pose(), home, 0.06), 40.0)
    time.sleep(0.5)
    t1 = time.monotonic()
    samples = watch.since(t0)
    towards = TowardsMonitor()
    min_c, contacts, touching = math.inf, 0, False
    behind_while_dodging = False
    with watch.lock:
        states = [(t, st) for t, st in watch.states if t0 <= t <= t1]
        arena = watch.arena
        events = [e for t, e in watch.events if t0 <= t <= t1]
    for t, rx, ry, ryaw, _, vx, vy in samples:
        people = crowd.people(t)
        d = min([footprint_clearance((rx, ry), ryaw, (p[1], p[2]), p[3]) for p in people] or [math.inf])
        min_c = min(min_c, d)
        contacts += d <= 0.0 and not touching
        touching = d <= 0.0
        towards.update(t, (rx, ry), ryaw, (vx, vy), people)
        state = next((st for ts, st in reversed(states) if ts <= t), "")
        if state == "DODGING" and any(p[0] == "visitor2" and footprint_clearance((rx, ry), ryaw, (p[1], p[2]), p[3])
                                      < towards.band for p in people):
            behind_while_dodging = True
    offsets = [math.hypot(q[1] - x, q[2] - y) for q in samples]
    exits = sum(1 for q in samples if arena and outside_polygon((q[1], q[2]), arena))
    end = watch.pose()
    run = {"speed_mps": v, "second_visitor": bool(second), "home": list(home), "min_clearance_m": min_c,
           "contacts": contacts, "max_offset_m": max(offsets) if offsets else 0.0, "dodge_max_m": dodge_max,
           "returned": bool(back), "final_offset_m": math.hypot(end[0] - x, end[1] - y),
           "arena_exit_samples": exits, "arena": arena, "states": [st for _, st in states], "events": events,
           "dodged": any(st == "DODGING" for _, st in states), "path": [(q[1], q[2]) for q in samples[::3]],
           "visitor": [(p[1], p[2]) for _, ps in crowd.track[::4] for p in ps if p[0] == "visitor"],
           "visitor2": [(p[1], p[2]) for _, ps in crowd.track[::4] for p in ps if p[0] == "visitor2"],
           "towards_checked": towards.checked,
           "max_towards_moving_person_mps": None if towards.checked == 0 else towards.max_towards,
           "towards_violations": [[round(t - t0, 2), n, round(vt, 3)] for t, n, vt in towards.violations],
           "second_visitor_started_in": second_started, "second_visitor_near_while_dodging": behind_while_dodging}
    log("visitor %.1f m/s%s: dodged %s, max offset %.3f m, min clearance %.3f m, contacts %d, back home %s "
        "(%.3f m), arena exits %d; towards a moving person: %d samples checked, max %s m/s, %d violations"
        % (v, " + a second one from behind" if second else "", run["dodged"], run["max_offset_m"], min_c, contacts,
           back, run["final_offset_m"], exits, towards.checked, run["max_towards_moving_person_mps"],
           len(towards.violations)))
    return run


def _speed(watch):
    with watch.lock:
        return watch.truth[-1][4] if watch.truth else 0.0


def _near(pose, home, tol):
    return pose is not None and math.hypot(pose[0] - home[0], pose[1] - home[1]) <= tol


def _rect(x, y, yaw, sx, sy):
    c, s = math.cos(yaw), math.sin(yaw)
    pts = [(sx / 2, sy / 2), (-sx / 2, sy / 2), (-sx / 2, -sy / 2), (sx / 2, -sy / 2), (sx / 2, sy / 2)]
    return [x + c * a - s * b for a, b in pts], [y + s * a + c * b for a, b in pts]


def plot(ctx, name, title, runs):
    """Ground-truth path, the obstacle, the planned detours and the arena, one panel per run."""
    import os

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(runs), figsize=(4.2 * len(runs), 4.0))
    for ax, r in zip(axes, runs):
        box = r.get("box") or r.get("wall")
        xs, ys = _rect(box[0], box[1], box[2], box[3], box[4])
        ax.fill(xs, ys, color="tab:brown", alpha=0.6, label="obstacle")
        if r.get("arena"):
            ax.plot([p[0] for p in r["arena"] + r["arena"][:1]], [p[1] for p in r["arena"] + r["arena"][:1]],
                    "k:", lw=1, label="arena")
        swept = r.get("swept") or []
        for i, rect in enumerate(swept[::max(1, len(swept) // 20)]):  # <= ~20 rectangles: readable
            ax.fill([p[0] for p in rect], [p[1] for p in rect], facecolor="none", edgecolor="tab:orange", lw=0.5,
                    alpha=0.7, label="stop zone swept on the detour (ground truth, grown)" if i == 0 else None)
        for i, plan in enumerate(r.get("plans", [])):
            if plan:
                ax.plot([p[0] for p in plan], [p[1] for p in plan], "o--", color="tab:purple", ms=3, lw=1,
                        label="planned detour" if i == 0 else None)
        if r.get("path"):
            ax.plot([p[0] for p in r["path"]], [p[1] for p in r["path"]], color="tab:blue", lw=1.3,
                    label="robot (ground truth)")
            ax.plot(r["path"][0][0], r["path"][0][1], "go", ms=5, label="start")
        state = "%s, avoidance %s" % (r.get("trick", "walk"), "on" if r.get("avoidance") else "off")
        extra = ("min clearance %.2f m" % r["min_clearance_m"]) if math.isfinite(r["min_clearance_m"]) else ""
        if not r.get("avoidance") and "stationary_s" in r:
            extra = "standing %.0f s (blocked)" % r["stationary_s"]
        ax.set_title("%s: %s\n%s" % (title, state, extra), fontsize=8)
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=6, loc="best")
        ax.set_xlabel("x [m]")
    path = os.path.join(ctx.out, name)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path


def plot_visitor(ctx, runs):
    """Robot path and visitor track per approach speed."""
    import os

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(runs), figsize=(4.2 * len(runs), 3.6), squeeze=False)
    for ax, r in zip(axes[0], runs):
        hx, hy = r["home"][:2]
        ax.add_patch(plt.Circle((hx, hy), r["dodge_max_m"], fill=False, ls="--", color="0.5", label="dodge_max"))
        ax.plot([p[0] for p in r["visitor"]], [p[1] for p in r["visitor"]], ".", color="tab:orange", ms=3,
                label="visitor centre")
        if r.get("visitor2"):
            ax.plot([p[0] for p in r["visitor2"]], [p[1] for p in r["visitor2"]], ".", color="tab:red", ms=3,
                    label="second visitor (from behind)")
        ax.plot([p[0] for p in r["path"]], [p[1] for p in r["path"]], color="tab:blue", lw=1.5,
                label="robot (ground truth)")
        ax.plot(hx, hy, "go", label="home")
        towards = r.get("max_towards_moving_person_mps")
        ax.set_title("%s at %.1f m/s: max offset %.2f m, min clearance %.2f m%s" % (
            "two visitors" if r.get("second_visitor") else "visitor", r["speed_mps"], r["max_offset_m"],
            r["min_clearance_m"], "" if towards is None else "\nmax speed towards a moving person %.2f m/s" % towards),
            fontsize=8)
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=6)
    path = os.path.join(ctx.out, "avoid_visitor.png")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path
