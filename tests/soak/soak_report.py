"""Crowd soak: ROS-free bookkeeping (memory trends, controller state counts, verdict, text report).

Used by ``tests/soak/run`` and unit-tested in ``tests/test_soak.py``.
"""

import collections
import math
import re
from typing import Dict, List, Optional, Sequence, Tuple

#: Memory is "flat" when, after the warm-up, a node's fitted RSS slope stays below
#: ``MEM_SLOPE_BOUND_MB_PER_H`` OR its RSS grew by less than ``MEM_GROWTH_BOUND_MB`` (end minus
#: start of the post-warm-up window): a short run cannot fail on the slope of a few noisy
#: samples, a long run cannot hide a steady leak behind a small absolute growth.
MEM_SLOPE_BOUND_MB_PER_H = 20.0
MEM_GROWTH_BOUND_MB = 8.0

_DIED = re.compile(r"\[([^\]]+)\] process has died")
_RESPAWN = re.compile(r"\[([^\]]+)\] restarting process")


def linear_slope(samples: Sequence[Tuple[float, float]]) -> float:
    """Least-squares slope dy/dt of (t, y) samples; 0 for fewer than two distinct times."""
    n = len(samples)
    if n < 2:
        return 0.0
    mt = sum(t for t, _ in samples) / n
    my = sum(y for _, y in samples) / n
    sxx = sum((t - mt) ** 2 for t, _ in samples)
    if sxx <= 0.0:
        return 0.0
    return sum((t - mt) * (y - my) for t, y in samples) / sxx


def memory_trend(
    samples: Sequence[Tuple[float, float]],
    warmup_s: float,
    slope_bound_mb_h: float = MEM_SLOPE_BOUND_MB_PER_H,
    growth_bound_mb: float = MEM_GROWTH_BOUND_MB,
) -> Dict[str, object]:
    """Summarise one node's RSS samples.

    Args:
        samples: (seconds since the soak started, RSS in MB), in time order.
        warmup_s: Samples before this time are ignored for slope and growth.
        slope_bound_mb_h: Slope bound [MB/h].
        growth_bound_mb: Absolute growth bound [MB].

    Returns:
        start/end RSS of the whole run and of the post-warm-up window, the post-warm-up slope
        [MB/h], the growth [MB] and ``flat`` (see the module constants).
    """
    if not samples:
        return {"samples": 0, "flat": True}
    window = [s for s in samples if s[0] >= warmup_s] or list(samples[-1:])
    slope = linear_slope(window) * 3600.0
    growth = window[-1][1] - window[0][1]
    flat = slope <= slope_bound_mb_h or growth <= growth_bound_mb
    return {
        "samples": len(samples),
        "start_mb": round(samples[0][1], 1),
        "after_warmup_mb": round(window[0][1], 1),
        "end_mb": round(samples[-1][1], 1),
        "max_mb": round(max(y for _, y in samples), 1),
        "slope_mb_per_h": round(slope, 2),
        "growth_after_warmup_mb": round(growth, 1),
        "flat": bool(flat),
    }


def launch_events(lines: Sequence[str]) -> Tuple[List[str], List[str]]:
    """Node deaths and respawns reported by roslaunch (process names like ``rbd_lidar-5``)."""
    died, respawned = [], []
    for line in lines:
        m = _DIED.search(line)
        if m:
            died.append(m.group(1))
        m = _RESPAWN.search(line)
        if m:
            respawned.append(m.group(1))
    return died, respawned


class StateCounter:
    """Counts tricks and collision stops from the controller's state stream."""

    def __init__(self) -> None:
        self.state = ""
        self.tricks_completed = 0
        self.collision_stops = 0
        self.collision_resumes = 0
        self.operator_lost = 0
        self.emergency_stops = 0
        self.last_completion: Optional[float] = None
        self.longest_gap_s = 0.0
        self._executed = False

    def update(self, t: float, state: str) -> None:
        """Feed one state message received at time t [s]."""
        prev, self.state = self.state, state
        if state == prev:
            return
        if state == "EXECUTING":
            self._executed = True
            if prev == "COLLISION_DETECTED":
                self.collision_resumes += 1
        elif state == "COLLISION_DETECTED":
            self.collision_stops += 1
        elif state == "OPERATOR_LOST":
            self.operator_lost += 1
        elif state == "EMERGENCY_STOP" and prev:
            self.emergency_stops += 1
        elif state == "WAITING_FOR_GESTURE" and self._executed:
            self._executed = False
            self.tricks_completed += 1
            if self.last_completion is not None:
                self.longest_gap_s = max(self.longest_gap_s, t - self.last_completion)
            self.last_completion = t


class BoxWatch:
    """What happened around each dropped box, so that every box contact can be explained.

    Fed with ground truth (pose and body twist), the controller's states and rbd_lidar's zone
    states, each with its time [s]; keeps a few seconds of each. A drop records how far from the
    footprint (and from the stop zone) the box landed and how fast the robot went; a contact
    records the state, the speed and direction of motion, how long after the drop it happened,
    when the zone first reported a collision after the drop and how far the robot moved after
    that, and the stale-zone reports just before it.

    Args:
        keep_s: seconds of history kept.
    """

    def __init__(self, keep_s: float = 10.0) -> None:
        self.keep_s = keep_s
        self.truth = collections.deque()  # (t, x, y, yaw, vx, vy, wz)
        self.zone = collections.deque()  # (t, collision, stale)
        self.states = collections.deque()  # (t, state)
        self.drops = []  # type: List[Dict[str, object]]
        self.contacts = []  # type: List[Dict[str, object]]
        self._first_collision = {}  # type: Dict[str, float]

    def _trim(self, buf: collections.deque, t: float) -> None:
        while buf and buf[0][0] < t - self.keep_s:
            buf.popleft()

    def on_truth(self, t: float, pose: Tuple[float, float, float], twist: Tuple[float, float, float]) -> None:
        """A ground-truth sample: pose (x, y, yaw) and body twist (vx, vy, wz)."""
        self.truth.append((t,) + tuple(pose) + tuple(twist))
        self._trim(self.truth, t)

    def on_zone(self, t: float, collision: bool, stale: bool) -> None:
        """A zone state of rbd_lidar."""
        self.zone.append((t, bool(collision), bool(stale)))
        self._trim(self.zone, t)
        if collision and self.drops:
            self._first_collision.setdefault(self.drops[-1]["name"], t)

    def on_state(self, t: float, state: str) -> None:
        """A controller state message."""
        if not self.states or self.states[-1][1] != state:
            self.states.append((t, state))
        self._trim(self.states, t)

    def state(self) -> str:
        """The latest controller state ("" before the first)."""
        return self.states[-1][1] if self.states else ""

    def on_drop(self, t: float, name: str, box: Sequence[float], gap: float, zone_gap: float) -> Dict[str, object]:
        """A box (x, y, yaw, size_x, size_y) dropped ``gap`` from the footprint, ``zone_gap`` from the zone."""
        last = self.truth[-1] if self.truth else None
        drop = {"name": name, "t": t, "box": [round(v, 3) for v in box], "gap_m": round(gap, 3),
                "zone_gap_m": round(zone_gap, 3), "state": self.state(),
                "speed_mps": round(math.hypot(last[4], last[5]), 3) if last else None}
        self.drops.append(drop)
        return drop

    def on_clearance(self, t: float, name: str, clearance: float) -> None:
        """Footprint-box clearance [m] of box ``name`` at t: the smallest per drop, with the state then."""
        drop = self.drops[-1] if self.drops and self.drops[-1]["name"] == name else None
        if drop is not None and t - drop["t"] <= 3.0 and clearance < drop.get("clearance_3s_m", math.inf):
            drop["clearance_3s_m"] = round(clearance, 3)  # the stop for the box: gap - this = stopping distance
        if drop is not None and clearance < drop.get("min_clearance_m", math.inf):
            drop["min_clearance_m"] = round(clearance, 3)
            drop["min_clearance_after_s"] = round(t - drop["t"], 2)
            drop["min_clearance_state"] = self.state()

    def on_contact(self, t: float, name: str) -> Dict[str, object]:
        """The footprint touched box ``name`` at t: the context of the contact."""
        drop = next((d for d in reversed(self.drops) if d["name"] == name), None)
        last = self.truth[-1] if self.truth else None
        first = self._first_collision.get(name)
        moved = None
        if first is not None and last is not None:
            after = [s for s in self.truth if s[0] >= first]
            if after:
                moved = round(math.hypot(last[1] - after[0][1], last[2] - after[0][2]), 3)
        info = {
            "t": round(t, 2), "box": name, "state": self.state(),
            "since_drop_s": None if drop is None else round(t - drop["t"], 2),
            "drop": drop,
            "body_twist": None if last is None else [round(v, 3) for v in last[4:7]],
            "states_since_drop": [(round(ts - drop["t"], 2), st) for ts, st in self.states
                                  if drop is not None and ts >= drop["t"] - 1.0],
            "first_zone_collision_after_drop_s": None if first is None or drop is None else round(first - drop["t"], 2),
            "moved_since_first_zone_collision_m": moved,
            "stale_zone_reports_last_3s": sum(1 for ts, _, st in self.zone if st and ts >= t - 3.0),
            "zone_collision_now": self.zone[-1][1] if self.zone else None,
        }
        self.contacts.append(info)
        return info


def verdict(report: Dict[str, object]) -> List[str]:
    """Reasons the soak failed (empty when it passed)."""
    reasons = []
    if report["contacts"]:
        reasons.append("%d contact(s) between the footprint and a person" % len(report["contacts"]))
    if report["node_deaths"] or report["respawns"] or report["vanished_nodes"]:
        reasons.append(
            "node crash: died %s, respawned %s, vanished %s"
            % (report["node_deaths"], report["respawns"], report["vanished_nodes"])
        )
    grown = sorted(n for n, m in report["memory"].items() if not m.get("flat", True))
    if grown:
        reasons.append("memory growth beyond the bound: %s" % ", ".join(grown))
    if report["tricks_completed"] < 1:
        reasons.append("no trick completed (the stack did not work)")
    if report.get("box_contacts"):
        reasons.append("%d contact(s) between the footprint and a dropped box" % len(report["box_contacts"]))
    if report.get("arena_exits"):
        reasons.append("the robot left the arena %d time(s)" % report["arena_exits"])
    if report.get("avoidance") == "on" and report.get("boxes_every_s") and report.get("blocked_forever"):
        reasons.append("blocked forever (stationary > 60 s with a trick pending) %d time(s)"
                       % len(report["blocked_forever"]))
    if report.get("error"):
        reasons.append("driver error: %s" % report["error"])
    return reasons


def render_text(report: Dict[str, object]) -> str:
    """Human-readable report."""
    min_c = report["min_clearance_m"]
    lines = [
        "RoboDog crowd soak: %s" % ("PASS" if report["passed"] else "FAIL"),
        "  command: %s" % report["command"],
        "  world: %s (seed %s, %d people, up to %.1f m/s)"
        % (report["world"], report["seed"], report["people"], report["max_person_speed"]),
        "  duration: %.0f s wall = %.0f s simulated (real time)" % (report["duration_s"], report["duration_s"]),
        "  tricks completed: %d %s (longest gap between completions %.0f s)"
        % (report["tricks_completed"], report["tricks_by_name"], report["longest_gap_between_tricks_s"]),
        "  gestures sent over the bridge: %d (heartbeat %.1f Hz)" % (report["gestures_sent"], report["heartbeat_hz"]),
        "  collision stops / resumes: %d / %d (rbd_lidar stale-cloud error lines: %d)"
        % (report["collision_stops"], report["collision_resumes"], report.get("lidar_stale_events", 0)),
        "  contacts footprint-person: %d" % len(report["contacts"]),
        "  min clearance footprint-person: %s" % ("n/a" if min_c is None else "%.2f m" % min_c),
        "  ground-truth samples: %d" % report["truth_samples"],
        "  boxes (issue 17): avoidance %s, %d dropped every %.0f s; box contacts %d, min box clearance %s; arena "
        "exits %d; blocked forever %d; obstacles avoided %d; gave up %d; tricks/hour %.1f"
        % (report.get("avoidance", "on"), report.get("boxes_dropped", 0), report.get("boxes_every_s", 0),
           len(report.get("box_contacts", [])), "n/a" if report.get("min_box_clearance_m") is None
           else "%.2f m" % report["min_box_clearance_m"], report.get("arena_exits", 0),
           len(report.get("blocked_forever", [])), report.get("obstacles_avoided", 0),
           len(report.get("avoidance_gave_up", [])), report.get("tricks_per_hour", 0.0)),
        "  node deaths / respawns / vanished: %s / %s / %s"
        % (report["node_deaths"], report["respawns"], report["vanished_nodes"]),
        "  memory (RSS MB, every %.0f s; warm-up %.0f s; flat = slope <= %.0f MB/h or growth <= %.0f MB):"
        % (report["memory_period_s"], report["warmup_s"], report["memory_slope_bound_mb_per_h"],
           report["memory_growth_bound_mb"]),
    ]
    for name in sorted(report["memory"]):
        m = report["memory"][name]
        if not m.get("samples"):
            continue
        lines.append(
            "    %-24s start %6.1f  after warm-up %6.1f  end %6.1f  slope %+7.2f MB/h  %s"
            % (name, m["start_mb"], m["after_warmup_mb"], m["end_mb"], m["slope_mb_per_h"],
               "flat" if m["flat"] else "GROWING")
        )
    for reason in report["failures"]:
        lines.append("  FAIL: %s" % reason)
    return "\n".join(lines)


def finite_or_none(x: float) -> Optional[float]:
    """x rounded to mm, or None when it is not finite (JSON has no inf)."""
    return round(x, 3) if math.isfinite(x) else None
