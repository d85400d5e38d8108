#!/usr/bin/env python3
"""Detour planner benchmark: rbd_controller's grid A* on the scenarios of the avoidance (issue 17).

Usage: planners.py OUTDIR [--export]

Scenarios (map frame, metres): a 0.4 m box on a 2 m path (the stroll experiment), a wall with a
gap, a floor with 6 random boxes. For each: plan time (p50 of 20 runs, CPU), path length over
the straight distance, smallest clearance of the path to the obstacle points. With --export the
inflated grids and start/goal go to OUTDIR/<scenario>.grid for ompl_compare (the same problem
for OMPL's sampling planners). Prints one JSON line per scenario.
"""

import json
import math
import os
import sys
import time

import numpy as np

from rbd_controller.detour import DetourPlanner, distance_field

RES = 0.05


def box(cx: float, cy: float, half: float, step: float = 0.02) -> list:
    """Points on the outline of a square box [m]."""
    pts = []
    for u in np.arange(-half, half + 1e-9, step):
        pts += [(cx + u, cy - half), (cx + u, cy + half), (cx - half, cy + u), (cx + half, cy + u)]
    return pts


def scenarios() -> dict:
    """Scenario name -> (start, goal, obstacle points)."""
    rng = np.random.default_rng(3)
    clutter = []
    for _ in range(6):
        cx, cy = rng.uniform(0.4, 3.6), rng.uniform(-1.5, 1.5)
        if math.hypot(cx - 0.0, cy) > 0.8 and math.hypot(cx - 4.0, cy) > 0.8:
            clutter += box(cx, cy, rng.uniform(0.1, 0.25))
    wall = [(1.5, y) for y in np.arange(-2.0, 0.6, 0.02)] + [(1.5, y) for y in np.arange(1.6, 2.5, 0.02)]
    return {
        "box_on_path": ((0.0, 0.0), (2.0, 0.0), box(1.0, 0.0, 0.2)),
        "wall_with_gap": ((0.0, 0.0), (3.0, 0.0), wall),
        "clutter": ((0.0, 0.0), (4.0, 0.0), clutter),
    }


def clearance(path: list, obstacles: list) -> float:
    """Smallest distance from the path's segments to the obstacle points [m]."""
    obs = np.asarray(obstacles)
    best = math.inf
    for a, b in zip(path, path[1:]):
        for u in np.linspace(0.0, 1.0, 40):
            p = np.array(a) + u * (np.array(b) - np.array(a))
            best = min(best, float(np.min(np.hypot(obs[:, 0] - p[0], obs[:, 1] - p[1]))))
    return best


def export(out: str, name: str, start: tuple, goal: tuple, obstacles: list, planner: DetourPlanner) -> None:
    """The inflated occupancy of the planning window as text: header, then rows of 0/1."""
    m = planner.window_margin
    x0, y0 = min(start[0], goal[0]) - m, min(start[1], goal[1]) - m
    x1, y1 = max(start[0], goal[0]) + m, max(start[1], goal[1]) + m
    w, h = int(math.ceil((x1 - x0) / RES)), int(math.ceil((y1 - y0) / RES))
    occ = np.zeros((h, w), dtype=bool)
    pts = np.asarray(obstacles)
    c = np.floor((pts[:, 0] - x0) / RES).astype(int)
    r = np.floor((pts[:, 1] - y0) / RES).astype(int)
    ok = (c >= 0) & (c < w) & (r >= 0) & (r < h)
    occ[r[ok], c[ok]] = True
    blocked = distance_field(occ, int(math.ceil(planner.inflation / RES))) * RES < planner.inflation
    with open(os.path.join(out, name + ".grid"), "w") as fh:
        fh.write("%d %d %.3f %.3f %.3f %.3f %.3f %.3f %.3f\n" % (w, h, x0, y0, RES, start[0], start[1], goal[0],
                                                               goal[1]))
        for row in blocked:
            fh.write("".join("1" if v else "0" for v in row) + "\n")
    np.savetxt(os.path.join(out, name + ".obstacles"), pts, fmt="%.3f")


def main() -> None:
    """Run the scenarios, print one JSON line each."""
    out = sys.argv[1] if len(sys.argv) > 1 else "."
    os.makedirs(out, exist_ok=True)
    planner = DetourPlanner(inflation=0.45, clearance=0.8)
    for name, (start, goal, obstacles) in scenarios().items():
        times = []
        plan = None
        for _ in range(20):
            t0 = time.process_time()
            plan = planner.plan(start, goal, points=obstacles)
            times.append(time.process_time() - t0)
        path = [start] + plan.waypoints
        row = {"planner": "grid A* (rbd_controller.detour)", "scenario": name, "ok": plan.ok,
               "time_ms_p50": round(1000 * sorted(times)[len(times) // 2], 1),
               "length_over_direct": round(plan.length / plan.direct, 3) if plan.ok else None,
               "min_clearance_m": round(clearance(path, obstacles), 3) if plan.ok else None,
               "waypoints": len(plan.waypoints), "expanded": plan.expanded}
        print(json.dumps(row), flush=True)
        if "--export" in sys.argv:
            export(out, name, start, goal, obstacles, planner)


if __name__ == "__main__":
    main()
