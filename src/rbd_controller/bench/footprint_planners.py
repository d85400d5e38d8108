#!/usr/bin/env python3
"""SE(2) footprint planner vs the disc grid A* on random scenes (issue 27).

Usage: footprint_planners.py [N] [SEED]   (default 40 scenes, seed 1; part of src/rbd_controller/bench/run)

Each scene: the robot 0.85 m behind the face of a 0.4 m box it was walking at (where the escape
leaves it), the goal 1.0-2.0 m beyond the box, 0-4 more boxes of 0.1-0.5 m at random in a 5 m x 4 m
window. For both planners: success, CPU time per plan, path length, and whether the path keeps
rbd_lidar's zone free of every box point when driven as the controller drives it: the disc plan pose
by pose (turn on the spot, walk straight at up to 0.3 m/s: the zone grown for that speed; turns: the
zone grown for the turn rate), the lattice plan with each motion's own planned speed and turn rate.
Prints one JSON line per planner with the totals.
"""

import json
import math
import sys
import time

import numpy as np

from rbd_controller.detour import DetourPlanner
from rbd_controller.footprint import ZoneGrowth, grown_zone, swept_hits
from rbd_controller.lattice import LatticePlanner

ZONE = (0.70, 0.35, 0.55, 0.35)


def box(cx: float, cy: float, half: float, step: float = 0.03) -> list:
    """Points on the outline of a square box [m]."""
    out = []
    for u in np.arange(-half, half + 1e-9, step):
        out += [(cx + u, cy - half), (cx + u, cy + half), (cx - half, cy + u), (cx + half, cy + u)]
    return out


def scene(rng: np.random.Generator) -> tuple:
    """(start pose, goal pose, obstacle points)."""
    pts = box(0.0, 0.0, 0.2)
    start = (-0.2 - 0.85, rng.uniform(-0.15, 0.15), rng.uniform(-0.2, 0.2))
    goal = (0.2 + rng.uniform(1.0, 2.0), rng.uniform(-0.5, 0.5), rng.uniform(-math.pi, math.pi))
    for _ in range(rng.integers(0, 5)):
        cx, cy, half = rng.uniform(-1.5, 3.0), rng.uniform(-2.0, 2.0), rng.uniform(0.05, 0.25)
        clear = 1.3 + half
        if math.hypot(cx - start[0], cy - start[1]) > clear and math.hypot(cx - goal[0], cy - goal[1]) > clear:
            pts += box(cx, cy, half)
    return start, goal, np.array(pts)


def disc_hits(start: tuple, goal: tuple, waypoints: list, pts: np.ndarray) -> int:
    """Box points in the zone when the disc plan is driven pose by pose (the issue 17 controller)."""
    g = ZoneGrowth()
    walk, turn = grown_zone(ZONE, 0.3, 0.0, 0.0, g), grown_zone(ZONE, 0.0, 0.0, math.radians(36.0), g)
    worst, pose = 0, start
    targets = list(waypoints[:-1]) + [goal[:2]]
    for x, y in targets:
        yaw = math.atan2(y - pose[1], x - pose[0]) if math.hypot(x - pose[0], y - pose[1]) > 1e-9 else pose[2]
        worst = max(worst, swept_hits([pose, (pose[0], pose[1], yaw)], turn, pts))
        worst = max(worst, swept_hits([(pose[0], pose[1], yaw), (x, y, yaw)], walk, pts))
        pose = (x, y, yaw)
    return max(worst, swept_hits([pose, goal], turn, pts))


def main() -> None:
    """Run the comparison and print the totals."""
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 40
    rng = np.random.default_rng(int(sys.argv[2]) if len(sys.argv) > 2 else 1)
    lattice, disc = LatticePlanner(ZONE), DetourPlanner(inflation=0.45, clearance=0.8)
    stats = {name: {"ok": 0, "cpu": [], "ratio": [], "zone_clear": 0} for name in ("lattice", "disc")}
    for _ in range(n):
        start, goal, pts = scene(rng)
        t0 = time.process_time()
        lp = lattice.plan(start, goal, points=pts)
        stats["lattice"]["cpu"].append(time.process_time() - t0)
        if lp.ok:
            s = stats["lattice"]
            s["ok"] += 1
            s["ratio"].append(lp.length / lp.direct)
            path = [start] + lp.poses
            s["zone_clear"] += all(swept_hits(path[i:i + 2], lp.zones[i], pts) == 0 for i in range(len(lp.poses)))
        t0 = time.process_time()
        dp = disc.plan(start[:2], goal[:2], points=pts)
        stats["disc"]["cpu"].append(time.process_time() - t0)
        if dp.ok:
            s = stats["disc"]
            s["ok"] += 1
            s["ratio"].append(dp.length / dp.direct)
            s["zone_clear"] += disc_hits(start, goal, dp.waypoints, pts) == 0
    for name, s in stats.items():
        print(json.dumps({
            "planner": name, "scenes": n, "found": s["ok"], "zone_kept_free": s["zone_clear"],
            "cpu_p50_s": round(float(np.median(s["cpu"])), 3), "cpu_max_s": round(float(np.max(s["cpu"])), 3),
            "length_over_direct_p50": round(float(np.median(s["ratio"])), 2) if s["ratio"] else None,
        }))


if __name__ == "__main__":
    main()
