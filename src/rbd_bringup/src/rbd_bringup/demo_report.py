"""The demo's report: what happened in a run, from ground truth and the A1's command stream.

ROS-free so the demo, its system test and the soak share one model of the figures.
"""

import json
import math
from typing import Dict, List, Optional, Sequence, Tuple


def reaction_times(collision_onsets: Sequence[float], commands: Sequence[Tuple[float, float]]) -> List[float]:
    """Software reaction time per collision onset: scan time → first zero-velocity command at the A1.

    Args:
        collision_onsets: stamps of the scans from which the zone demanded a stop [s] (the rising
            edges of :func:`stop_demanded`; a guarded motion away from an intruder is no stop).
        commands: (time [s], commanded speed magnitude) of every HighCmd seen on LCM, in order.

    Returns:
        One reaction time [s] per onset at which the robot was commanded to move (onsets while
        already standing still have nothing to stop and are skipped).
    """
    out = []
    for onset in collision_onsets:
        before = [speed for t, speed in commands if t <= onset]
        if not before or before[-1] < 1e-6:
            continue
        after = [t for t, speed in commands if t > onset and speed < 1e-6]
        if after:
            out.append(after[0] - onset)
    return out


#: Side order of rbd_msgs/CollisionState's ``points`` (FRONT, LEFT, BACK, RIGHT).
FRONT, LEFT, BACK, RIGHT = 0, 1, 2, 3
#: Controller states whose motions are gated per zone side (DESIGN: an avoidance motion starts with
#: something in the zone and may only move away from it), not stopped by the collision flag.
GUARDED_STATES = ("ESCAPING", "DODGING")


def heading_sides(vx: float, vy: float, wz: float, eps: float = 1e-3) -> List[int]:
    """Zone sides a body velocity moves towards (a turn sweeps all four).

    Written here on purpose rather than imported from rbd_pos_controller's zone guard
    (``sides_towards``, the same rule): the report measures whether the guard stopped what it
    had to, from the HighCmd stream, so it does not share the guard's code.

    Args:
        vx: forward velocity [m/s].
        vy: leftward velocity [m/s].
        wz: yaw rate [rad/s].
        eps: smaller magnitudes count as zero.

    Returns:
        Side indices (FRONT, LEFT, BACK, RIGHT) in that order.
    """
    if abs(wz) > eps:
        return [FRONT, LEFT, BACK, RIGHT]
    sides = []
    if vx > eps:
        sides.append(FRONT)
    elif vx < -eps:
        sides.append(BACK)
    if vy > eps:
        sides.append(LEFT)
    elif vy < -eps:
        sides.append(RIGHT)
    return sorted(sides)


def stop_demanded(
    collision: bool, points: Sequence[int], velocity: Tuple[float, float, float], state: str, point_threshold: int = 5
) -> bool:
    """Whether a zone reading demands that the current motion stops.

    A trick motion (every state but the guarded ones) must stop on the collision flag. A guarded
    avoidance motion (ESCAPING, DODGING) is allowed to move away from what is in the zone; it must
    stop when a side it heads towards holds ``point_threshold`` critical points (rbd_lidar's rule).

    Args:
        collision: the reading's collision flag.
        points: critical points per side (FRONT, LEFT, BACK, RIGHT).
        velocity: (vx, vy, wz) the A1 was last commanded before the scan.
        state: the main controller's state at the scan.
        point_threshold: critical points that make a side occupied (rbd_lidar ``~point_threshold``).

    Returns:
        True when the zone demands zero velocity.
    """
    if state not in GUARDED_STATES:
        return bool(collision)
    return any(int(points[s]) >= point_threshold for s in heading_sides(*velocity))


class StopOnsets:
    """Scan stamps from which the zone demanded a stop: the rising edges of :func:`stop_demanded`.

    Args:
        point_threshold: critical points that make a side occupied (rbd_lidar ``~point_threshold``).
    """

    def __init__(self, point_threshold: int = 5) -> None:
        self.point_threshold = int(point_threshold)
        self.onsets = []  # type: List[float]
        self._demanded = False

    def update(self, stamp: float, collision: bool, points: Sequence[int], valid: bool,
               velocity: Tuple[float, float, float], state: str) -> bool:
        """One zone reading; True (and its stamp appended to :attr:`onsets`) when it starts a demanded stop.

        Args:
            stamp: the scan's stamp [s].
            collision: the reading's collision flag.
            points: critical points per side.
            valid: False for a stale or erroneous reading (never an onset: it is a sensor stop).
            velocity: (vx, vy, wz) last commanded to the A1 at or before the scan.
            state: the main controller's state.
        """
        demanded = valid and stop_demanded(collision, points, velocity, state, self.point_threshold)
        onset = demanded and not self._demanded
        self._demanded = demanded
        if onset:
            self.onsets.append(stamp)
        return onset


def percentile(values: Sequence[float], q: float) -> Optional[float]:
    """The q-th percentile (0..100, nearest rank) or None for no values."""
    if not values:
        return None
    ordered = sorted(values)
    rank = max(0, min(len(ordered) - 1, int(math.ceil(q / 100.0 * len(ordered))) - 1))
    return ordered[rank]


def build_report(
    tricks_requested: Sequence[str],
    tricks_completed: Sequence[str],
    contacts: Sequence[Tuple[float, str]],
    min_clearance: float,
    state_log: Sequence[Tuple[float, str]],
    start_pose: Tuple[float, float, float],
    final_pose: Tuple[float, float, float],
    reactions: Sequence[float],
    scan_period: float,
    duration: float,
    avoidance_events: Sequence[str] = (),
    obstacle_contacts: Sequence[Tuple[float, str]] = (),
    min_obstacle_clearance: float = math.inf,
    gesture_input: str = "",
) -> Dict:
    """Collect the run's figures into one JSON-able dictionary.

    Args:
        tricks_requested: trick commands the scripted audience showed.
        tricks_completed: tricks that ran to the end (back to WAITING_FOR_GESTURE).
        contacts: (time, person) of every footprint contact from ground truth.
        min_clearance: smallest footprint-to-person clearance seen [m].
        state_log: (time, state) of every main-controller state change.
        start_pose: ground-truth (x, y, yaw) when the e-stop was released.
        final_pose: ground-truth (x, y, yaw) at the end.
        reactions: software reaction times [s] (see :func:`reaction_times`).
        scan_period: LiDAR scan period [s].
        duration: wall time of the scripted part [s].
        avoidance_events: the controller's ``/rbd_controller/avoidance`` lines ("avoided: ...",
            "gave_up: ...", ...).
        obstacle_contacts: (time, obstacle) of every footprint contact with a placed box.
        min_obstacle_clearance: smallest footprint-to-box clearance seen [m].
        gesture_input: what the gestures were made from (said plainly in the report).

    Returns:
        The report.
    """
    states = [s for _, s in state_log]
    stops = sum(1 for s in states if s in ("COLLISION_DETECTED", "EMERGENCY_STOP"))
    resumes = sum(
        1 for a, b in zip(states, states[1:])
        if a in ("COLLISION_DETECTED", "EMERGENCY_STOP", "BLOCKED") and b == "EXECUTING"
    )
    dyaw = math.atan2(math.sin(final_pose[2] - start_pose[2]), math.cos(final_pose[2] - start_pose[2]))
    p99 = percentile(reactions, 99)
    blocked, avoiding = time_in(state_log, BLOCKED_STATES), time_in(state_log, AVOIDING_STATES)
    return {
        "obstacles_avoided": sum(1 for e in avoidance_events if e.startswith("avoided")),
        "avoidance_gave_up": [e for e in avoidance_events if e.startswith("gave_up")],
        "time_blocked_s": round(blocked, 1),
        "time_avoiding_s": round(avoiding, 1),
        "collisions_with_obstacles": len(obstacle_contacts),
        "min_distance_to_obstacle_m": None if math.isinf(min_obstacle_clearance) else round(
            min_obstacle_clearance, 3),
        "tricks_requested": list(tricks_requested),
        "tricks_completed": list(tricks_completed),
        "collisions_with_people": len(contacts),
        "contacts": [{"t": round(t, 3), "person": p} for t, p in contacts],
        "min_distance_to_person_m": None if math.isinf(min_clearance) else round(min_clearance, 3),
        "stops": stops,
        "resumes": resumes,
        "collision_stops": states.count("COLLISION_DETECTED"),
        "final_position_error_m": round(math.hypot(final_pose[0] - start_pose[0], final_pose[1] - start_pose[1]), 3),
        "final_yaw_error_deg": round(math.degrees(abs(dyaw)), 2),
        "reaction_times_s": [round(r, 4) for r in reactions],
        "reaction_p50_s": None if not reactions else round(percentile(reactions, 50), 4),
        "reaction_p99_s": None if p99 is None else round(p99, 4),
        "reaction_goal_s": round(scan_period + 0.020, 4),
        "duration_s": round(duration, 1),
        "gesture_input": gesture_input,
        "states": [{"t": round(t, 3), "state": s} for t, s in state_log],
    }


#: Stopped by something in the zone (a person, or a static obstacle before or without avoidance).
BLOCKED_STATES = ("COLLISION_DETECTED", "BLOCKED")
#: Getting around a static obstacle.
AVOIDING_STATES = ("ESCAPING", "AVOIDING")


def time_in(state_log: Sequence[Tuple[float, str]], states: Sequence[str]) -> float:
    """Seconds the controller spent in any of states (state changes (time, state), in order)."""
    total = 0.0
    for (t0, s0), (t1, _s1) in zip(state_log, state_log[1:]):
        if s0 in states:
            total += t1 - t0
    return total


def render_text(report: Dict) -> str:
    """Human-readable report (the demo's last screen and report.txt)."""
    lines = [
        "RoboDog demo report",
        "===================",
        "tricks completed:        %d of %d (%s)" % (
            len(report["tricks_completed"]), len(report["tricks_requested"]), ", ".join(report["tricks_completed"])),
        "collisions with people:  %d (ground truth, robot footprint vs person cylinders)" % report[
            "collisions_with_people"],
        "min distance to person:  %s m" % report["min_distance_to_person_m"],
        "stops / resumes:         %d / %d (collision stops: %d)" % (
            report["stops"], report["resumes"], report["collision_stops"]),
        "obstacles avoided:       %d (%d pose(s) skipped), contacts with obstacles %d, min distance %s m" % (
            report.get("obstacles_avoided", 0), len(report.get("avoidance_gave_up", [])),
            report.get("collisions_with_obstacles", 0), report.get("min_distance_to_obstacle_m")),
        "time blocked:            %.1f s stopped by people or obstacles, %.1f s getting around obstacles" % (
            report.get("time_blocked_s", 0.0), report.get("time_avoiding_s", 0.0)),
        "final pose error:        %.3f m, %.1f deg (ground truth vs start)" % (
            report["final_position_error_m"], report["final_yaw_error_deg"]),
        "software reaction time:  p50 %s s, p99 %s s over %d stops (goal <= %s s: one scan + 20 ms)" % (
            report["reaction_p50_s"], report["reaction_p99_s"], len(report["reaction_times_s"]),
            report["reaction_goal_s"]),
        "duration:                %.1f s" % report["duration_s"],
    ]
    if report.get("gesture_input"):
        lines.append("gesture input:           %s" % report["gesture_input"])
    return "\n".join(lines) + "\n"


def write_report(report: Dict, out_dir: str) -> None:
    """Write report.json and report.txt into out_dir."""
    with open("%s/report.json" % out_dir, "w") as fh:
        json.dump(report, fh, indent=2)
    with open("%s/report.txt" % out_dir, "w") as fh:
        fh.write(render_text(report))


def plot_run(path_xy: Sequence[Tuple[float, float]], people: Dict[str, List[Tuple[float, float, float]]],
             stop_points: Sequence[Tuple[float, float]], png: str,
             boxes: Sequence[Tuple[float, float, float, float, float]] = (),
             detours: Sequence[Sequence[Tuple[float, float]]] = ()) -> None:
    """PNG of the run: the robot's ground-truth path, where people stood, where it stopped.

    Args:
        path_xy: ground-truth positions [m].
        people: person name -> list of (x, y, radius) samples.
        stop_points: robot positions at collision stops [m].
        png: output file.
        boxes: placed boxes (x, y, yaw, size_x, size_y) [m, rad].
        detours: planned detours (the controller's /rbd_controller/detour), each a list of (x, y).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 6))
    if path_xy:
        xs, ys = zip(*path_xy)
        ax.plot(xs, ys, "-", color="tab:blue", lw=1.5, label="robot (ground truth)")
        ax.plot(xs[0], ys[0], "o", color="tab:green", label="start")
    for i, (_name, samples) in enumerate(sorted(people.items())):
        px = [s[0] for s in samples]
        py = [s[1] for s in samples]
        ax.plot(px, py, ".", ms=2, color="tab:orange", alpha=0.4, label="people" if i == 0 else None)
        ax.add_patch(plt.Circle((px[-1], py[-1]), samples[-1][2], color="tab:orange", fill=False))
    for i, (bx, by, byaw, lx, ly) in enumerate(boxes):
        c, s = math.cos(byaw), math.sin(byaw)
        corners = [(lx / 2, ly / 2), (-lx / 2, ly / 2), (-lx / 2, -ly / 2), (lx / 2, -ly / 2), (lx / 2, ly / 2)]
        ax.fill([bx + c * u - s * v for u, v in corners], [by + s * u + c * v for u, v in corners], color="tab:brown",
                alpha=0.7, label="bag (static obstacle)" if i == 0 else None)
    for i, plan in enumerate(d for d in detours if d):
        ax.plot([p[0] for p in plan], [p[1] for p in plan], "o--", color="tab:purple", ms=3, lw=1,
                label="planned detour" if i == 0 else None)
    if stop_points:
        sx, sy = zip(*stop_points)
        ax.plot(sx, sy, "x", color="red", ms=10, mew=2, label="collision stop")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("RoboDog demo run")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)
