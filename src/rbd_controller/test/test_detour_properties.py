"""Property tests of the detour planner over randomized scenes, degenerate ones included (issue 27).

The planner runs inside the main controller's tick: any exception there kills the node (the soak's
``IndexError`` at ``waypoints[-1] = ...`` when start and goal fell in one cell). Every scene must give
a Plan; a found plan must end at the goal, stay inside the arena and keep the inflation.
"""

import math

import numpy as np
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from rbd_controller.arena import Arena
from rbd_controller.detour import DetourPlanner, GridMap, finite_points, zone_occupied_at

RES = 0.05
INFLATION = 0.3
PLANNER = DetourPlanner(inflation=INFLATION, clearance=0.5, resolution=RES, window_margin=1.0, max_expansions=20000)
SETTINGS = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])

coord = st.floats(-2.5, 2.5, allow_nan=False)
maybe_bad = st.one_of(coord, st.sampled_from([math.nan, math.inf, -math.inf]))
point = st.tuples(coord, coord)
bad_point = st.tuples(maybe_bad, maybe_bad)


def box(cx, cy, half, step=0.04):
    out = []
    for u in np.arange(-half, half + 1e-9, step):
        out += [(cx + u, cy - half), (cx + u, cy + half), (cx - half, cy + u), (cx + half, cy + u)]
    return out


@st.composite
def scenes(draw):
    """start, goal, obstacle points, grid, arena; with a bias towards the degenerate cases."""
    start = draw(point)
    kind = draw(st.sampled_from(["random", "same", "same_cell", "near"]))
    if kind == "same":
        goal = start
    elif kind == "same_cell":
        goal = (start[0] + draw(st.floats(-0.02, 0.02)), start[1] + draw(st.floats(-0.02, 0.02)))
    elif kind == "near":
        goal = (start[0] + draw(st.floats(-0.3, 0.3)), start[1] + draw(st.floats(-0.3, 0.3)))
    else:
        goal = draw(point)
    pts = []
    for _ in range(draw(st.integers(0, 3))):
        pts += box(draw(coord), draw(coord), draw(st.floats(0.02, 0.4)))
    pts += draw(st.lists(bad_point, max_size=5))
    if draw(st.booleans()):  # an obstacle right at the start (start inside the inflation)
        pts += box(start[0] + draw(st.floats(-0.3, 0.3)), start[1] + draw(st.floats(-0.3, 0.3)), 0.1)
    grid = None
    if draw(st.booleans()):
        h, w = draw(st.integers(0, 60)), draw(st.integers(0, 60))
        occ = np.random.default_rng(draw(st.integers(0, 1000))).random((h, w)) < draw(st.floats(0.0, 0.05))
        grid = GridMap(occ, (draw(coord), draw(coord)), draw(st.sampled_from([0.05, 0.1])))
    arena = None
    if draw(st.booleans()):
        x0, y0 = draw(st.floats(-3.0, 0.0)), draw(st.floats(-3.0, 0.0))
        arena = Arena.rectangle(x0, y0, x0 + draw(st.floats(0.2, 5.0)), y0 + draw(st.floats(0.2, 5.0)))
        if draw(st.booleans()):  # the goal on the arena's edge
            goal = (x0, goal[1])
    return start, goal, pts, grid, arena


def clearance(a, b, obstacles):
    """Smallest distance from the segment a-b (sampled) to the obstacle points."""
    if not len(obstacles):
        return math.inf
    u = np.linspace(0.0, 1.0, max(2, int(math.hypot(b[0] - a[0], b[1] - a[1]) / 0.01) + 1))
    seg = np.stack([a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])], axis=1)
    d = np.hypot(seg[:, None, 0] - obstacles[None, :, 0], seg[:, None, 1] - obstacles[None, :, 1])
    return float(d.min())


def obstacles_of(pts, grid, window):
    obs = [finite_points(pts)]
    if grid is not None and grid.occupied.size:
        r, c = np.nonzero(grid.occupied)
        res = grid.resolution
        centres = np.stack([grid.origin[0] + (c + 0.5) * res, grid.origin[1] + (r + 0.5) * res], 1)
        # A map cell is an obstacle wherever the planner's cell centre falls in it: its whole square.
        obs.append(centres.reshape(-1, 2))
    out = np.concatenate(obs).reshape(-1, 2)
    x0, y0, x1, y1 = window
    keep = (out[:, 0] >= x0) & (out[:, 0] <= x1) & (out[:, 1] >= y0) & (out[:, 1] <= y1)
    return out[keep]


@SETTINGS
@given(scenes())
def test_every_scene_gives_a_plan_and_a_found_plan_is_sound(scene):
    start, goal, pts, grid, arena = scene
    plan = PLANNER.plan(start, goal, grid=grid, points=pts, arena=arena)
    assert not plan.reason.startswith("planner error"), plan.reason
    if not plan.ok:
        assert plan.waypoints == [] and plan.reason
        return
    assert plan.waypoints and plan.waypoints[-1] == (float(goal[0]), float(goal[1]))
    assert all(math.isfinite(v) for p in plan.waypoints for v in p)
    assert plan.length >= plan.direct - 1e-9
    path = [tuple(start)] + plan.waypoints
    if arena is not None:
        # Waypoints are cell centres inside the arena (the goal itself is checked by contains()).
        assert all(arena.contains(*p) or arena.edge_distance(*p) < RES for p in path[1:])
    m = PLANNER.window_margin
    window = (min(start[0], goal[0]) - m, min(start[1], goal[1]) - m, max(start[0], goal[0]) + m,
              max(start[1], goal[1]) + m)
    obs = obstacles_of(pts, grid, window)
    if not len(obs) or clearance(start, start, obs) < INFLATION + 2 * RES:
        return  # a start inside the inflation may leave through it (the escape's remainder)
    # Discretisation: an obstacle anywhere in its cell, the path anywhere in a free cell (and the
    # map's cells are coarser): at most one map cell diagonal and one planning cell diagonal lost.
    slack = (0.1 if grid is not None else RES) * math.sqrt(2) / 2 + RES * math.sqrt(2)
    for a, b in zip(path, path[1:]):
        assert clearance(a, b, obs) >= INFLATION - slack, (a, b)


@SETTINGS
@given(point, st.lists(bad_point, max_size=40))
def test_start_equal_goal_is_a_plan_of_the_goal_alone(start, pts):
    plan = PLANNER.plan(start, start, points=pts)
    if plan.ok:
        assert plan.waypoints == [(float(start[0]), float(start[1]))] and plan.length == 0.0
    else:
        assert "goal blocked" in plan.reason  # the only reason left: an obstacle at the goal


def test_start_and_goal_in_one_cell_was_the_soak_crash():
    # The soak: the A* path of one cell left no waypoint to replace with the goal (IndexError).
    plan = PLANNER.plan((0.012, 0.013), (0.021, 0.024), points=box(2.0, 2.0, 0.2))
    assert plan.ok and plan.waypoints == [(0.021, 0.024)]


@SETTINGS
@given(maybe_bad, maybe_bad, maybe_bad, maybe_bad)
def test_non_finite_start_or_goal_is_refused_with_a_reason(sx, sy, gx, gy):
    assume(not all(math.isfinite(v) for v in (sx, sy, gx, gy)))
    plan = PLANNER.plan((sx, sy), (gx, gy), points=box(0.0, 0.0, 0.2))
    assert not plan.ok and "not finite" in plan.reason


def test_far_goal_is_refused_not_a_huge_window():
    plan = PLANNER.plan((0.0, 0.0), (1e7, 0.0))
    assert not plan.ok and "beyond" in plan.reason


def test_empty_scene_is_the_straight_line():
    plan = PLANNER.plan((0.0, 0.0), (1.5, 0.5))
    assert plan.ok and plan.waypoints == [(1.5, 0.5)]
    assert abs(plan.length - plan.direct) < 1e-9


def test_zone_check_ignores_non_finite_points():
    assert zone_occupied_at((0.0, 0.0, 0.0), (0.7, 0.35, 0.55, 0.35), [(math.nan, 0.0), (0.3, 0.0)]) == 1
