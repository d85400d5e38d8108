"""Property tests of the avoidance decisions over randomized scenes (issue 27), no ROS master.

Every decision rbd_controller makes about obstacles -- classification (blocking, perception),
escape, dodge, arena -- and the controller's tick itself, over random scenes including degenerate
ones: no points, NaN/inf coordinates and distances, the robot on the arena's edge or outside it,
home = pose, zero-length steps, clocks going back. Properties: nothing raises (a crash in a tick is
a failure, not a respawn), every answer is one of the documented ones, and every motion target is
finite, inside the arena and within its limits.

Examples per property: ``RBD_FUZZ_EXAMPLES`` (default 25), e.g.
``RBD_FUZZ_EXAMPLES=5000 pytest -c pytest.ini src/rbd_controller/test/test_avoidance_properties.py``.
"""

import math
import os

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rbd_controller.arena import Arena, default_arena
from rbd_controller.blocking import CLEAR, MOVING, STATIC, UNKNOWN, BlockClassifier, near_fraction
from rbd_controller.core import MainController, Ports
from rbd_controller.detour import GridMap
from rbd_controller.dodge import ApproachDetector, dodge_target
from rbd_controller.escape import ZoneReading, clear_by_margin, occupied_sides, plan_escape
from rbd_controller.fsm import State
from rbd_controller.perception import AvoidParams, Perception
from rbd_controller.planner_worker import PlannerWorker

EXAMPLES = int(os.environ.get("RBD_FUZZ_EXAMPLES", "25"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much])

ZONE = (0.70, 0.35, 0.55, 0.35)
anything = st.floats(allow_nan=True, allow_infinity=True)
coord = st.one_of(st.floats(-5.0, 5.0), anything)
small = st.floats(-3.0, 3.0)
point = st.tuples(coord, coord)
scan = st.one_of(st.just([]), st.lists(point, max_size=12),
                 st.lists(st.tuples(small, small), min_size=1, max_size=25))
distance = st.one_of(st.floats(0.0, 3.0), anything)
reading = st.builds(ZoneReading, st.lists(st.integers(-3, 50), min_size=4, max_size=4),
                    st.lists(distance, min_size=4, max_size=4), st.booleans(),
                    st.sampled_from(["", "malformed cloud"]))
pose = st.tuples(small, small, st.floats(-7.0, 7.0))
side = st.integers(0, 3)
_half = np.zeros((20, 20), dtype=bool)
_half[:, 10:] = True
GRIDS = [  # an empty map, one never explored, one all free and known, one half occupied
    GridMap(np.zeros((0, 0), dtype=bool), (0.0, 0.0), 0.05, known=np.zeros((0, 0), dtype=bool)),
    GridMap(np.zeros((20, 20), dtype=bool), (-0.5, -0.5), 0.05, known=np.zeros((20, 20), dtype=bool)),
    GridMap(np.zeros((20, 20), dtype=bool), (-0.5, -0.5), 0.05, known=np.ones((20, 20), dtype=bool)),
    GridMap(_half, (0.0, -0.5), 0.05, known=np.ones((20, 20), dtype=bool)),
]


@st.composite
def arenas(draw):
    """A random arena: a rectangle, a triangle or a convex-ish polygon, sometimes tiny."""
    kind = draw(st.sampled_from(["rect", "tri", "poly", "none"]))
    if kind == "none":
        return None
    if kind == "rect":
        x0, y0 = draw(small), draw(small)
        w, h = draw(st.floats(0.01, 6.0)), draw(st.floats(0.01, 6.0))
        return Arena.rectangle(x0, y0, x0 + w, y0 + h)
    n = 3 if kind == "tri" else draw(st.integers(4, 8))
    cx, cy, r = draw(small), draw(small), draw(st.floats(0.05, 4.0))
    angles = sorted(draw(st.lists(st.floats(0.0, 2 * math.pi), min_size=n, max_size=n, unique=True)))
    verts = [(cx + r * math.cos(a), cy + r * math.sin(a)) for a in angles]
    try:
        return Arena(verts)
    except ValueError:
        return None  # collinear: the constructor refuses it with a clear error


def finite(*values):
    return all(math.isfinite(v) for v in values)


# ------------------------------------------------------------------------------ classification
@FUZZ
@given(st.lists(st.tuples(st.floats(-1.0, 30.0), scan), max_size=15), st.one_of(st.none(), scan),
       st.booleans(), st.floats(0.1, 8.0))
def test_classification_never_raises_and_answers_one_of_four(scans, known, with_map, static_after):
    c = BlockClassifier(static_after=static_after)
    occupied = (lambda x, y: bool(math.isfinite(x) and x > 0.0)) if with_map else None
    known_arr = None if known is None else np.asarray(known, dtype=np.float64).reshape(-1, 2)
    for t, pts in scans:
        c.update(t, pts)
        result = c.classify(occupied, known_arr)
        assert result in (CLEAR, UNKNOWN, STATIC, MOVING) and isinstance(c.reason, str)
        if not len([p for p in pts if finite(*p)]):
            assert result == CLEAR
        assert not c.known_match or result == STATIC


@FUZZ
@given(st.lists(st.tuples(small, small), max_size=40), st.lists(st.tuples(small, small), max_size=40),
       st.floats(0.01, 1.0))
def test_near_fraction_is_a_fraction(a, b, radius):
    f = near_fraction(np.asarray(a, dtype=np.float64).reshape(-1, 2), np.asarray(b, dtype=np.float64).reshape(-1, 2),
                      radius)
    assert 0.0 <= f <= 1.0
    if a and a == b:
        assert f == 1.0


@FUZZ
@given(st.lists(st.tuples(st.sampled_from(["pose", "zone", "blocking", "scan", "classify", "remember", "forget",
                                           "arena", "map"]),
                          pose, reading, scan, st.tuples(coord, coord, coord), st.sampled_from(GRIDS)), max_size=15))
def test_perception_never_raises_and_keeps_its_outputs_finite(steps):
    p = Perception(AvoidParams(static_after=0.5))
    t = 0.0
    built_for = None  # the home the arena was last built around
    for kind, good_pose, zone, pts, raw_pose, grid in steps:
        t += 0.1
        if kind == "map":
            p.on_map(grid)
        elif kind == "pose":
            p.on_pose(t, *raw_pose)
            p.on_pose(t, *good_pose)
        elif kind == "zone":
            p.on_zone(t, zone)
        elif kind == "blocking":
            p.on_blocking_points(t, pts)
        elif kind == "scan":
            p.on_scan_points(t, pts)
        elif kind == "classify":
            result, reason = p.classify()
            assert result in (CLEAR, UNKNOWN, STATIC, MOVING) and isinstance(reason, str)
        elif kind == "remember":
            p.remember_static()
        elif kind == "forget":
            p.forget_static()
        else:
            # The arena is built once, around the first home it is asked for (again when the first
            # map arrives); a later call with another home returns it unchanged.
            home = good_pose[:2]
            before = p.arena
            arena = p.ensure_arena(home)
            if arena is not before:
                built_for = home
            assert arena.contains(*built_for)
        assert p.pose is None or finite(*p.pose)
        obstacles = p.obstacles(t - 5.0)
        assert obstacles.shape[1] == 2 and np.all(np.isfinite(obstacles))
        assert np.all(np.isfinite(p.known_static))
        assert all(s in range(4) for s in p.recently_approached(t))


# ------------------------------------------------------------------------------ escape
@FUZZ
@given(reading, pose, st.integers(1, 10), st.floats(0.0, 0.5), st.floats(0.05, 1.5), arenas())
def test_escape_never_raises_and_never_heads_into_an_occupied_side(r, robot, threshold, margin, max_distance, arena):
    esc, why = plan_escape(r, ZONE, robot, threshold, margin, max_distance, arena=arena)
    assert isinstance(why, str)
    clear = clear_by_margin(r, ZONE, threshold, margin)
    assert clear == (r.valid and not occupied_sides(r, ZONE, threshold, margin))
    if esc is None:
        assert why
        return
    assert r.valid and not clear
    assert finite(*esc.target) and 0.05 - 1e-9 <= esc.distance <= max_distance + 1e-9
    assert math.hypot(esc.target[0] - robot[0], esc.target[1] - robot[1]) <= max_distance + 1e-6
    assert esc.side not in occupied_sides(r, ZONE, threshold, 0.0)  # never towards an occupied side
    if arena is not None:
        assert arena.contains(*esc.target)


def test_escape_with_a_nan_pose_is_refused():
    r = ZoneReading([10, 0, 0, 0], [0.3, math.inf, math.inf, math.inf])
    esc, why = plan_escape(r, ZONE, (float("nan"), 0.0, 0.0), 1)
    assert esc is None and "pose" in why


# ------------------------------------------------------------------------------ dodge
@FUZZ
@given(st.tuples(small, small), pose, side, st.floats(0.0, 1.0), st.floats(0.0, 1.0), arenas())
def test_dodge_target_never_raises_stays_near_home_and_in_the_arena(home, robot, approached, step, max_offset, arena):
    target, why = dodge_target(home, robot, approached, step, max_offset, arena)
    assert isinstance(why, str) and why
    if target is None:
        return
    assert finite(*target)
    assert math.hypot(target[0] - robot[0], target[1] - robot[1]) <= step + 1e-6
    away_from_home = math.hypot(robot[0] - home[0], robot[1] - home[1])
    assert math.hypot(target[0] - home[0], target[1] - home[1]) <= max(max_offset, away_from_home) + 1e-6
    if arena is not None:
        assert arena.contains(*target)
    # It steps away from the approached side: the body-frame motion has no component towards it.
    dx, dy = target[0] - robot[0], target[1] - robot[1]
    c, s = math.cos(robot[2]), math.sin(robot[2])
    bx, by = c * dx + s * dy, -s * dx + c * dy
    towards = {0: bx, 1: by, 2: -bx, 3: -by}[approached]
    assert towards <= 1e-9


@FUZZ
@given(st.lists(st.tuples(st.floats(-1.0, 20.0), st.lists(distance, min_size=4, max_size=4),
                          st.tuples(anything, anything)), max_size=20))
def test_approach_detector_never_raises(updates):
    det = ApproachDetector([z + s for z, s in zip(ZONE, (0.5, 0.2, 0.3, 0.2))])
    for t, dists, own in updates:
        sides = det.update(t, dists, own)
        assert all(s in range(4) for s in sides)
        assert not math.isnan(det.quiet_for(t))


# ------------------------------------------------------------------------------ arena
@FUZZ
@given(arenas(), point, point, st.floats(0.0, 3.0), st.floats(0.0, 0.5))
def test_arena_queries_never_raise_and_reach_stays_inside(arena, start, direction, dist, margin):
    if arena is None:
        return
    arena.contains(*start)
    arena.edge_distance(*start)
    arena.segment_inside(start, direction)
    d = arena.reach(start, direction, dist, margin)
    assert 0.0 <= d <= dist + 1e-9
    if d > 0.0:
        assert arena.contains(start[0] + d * direction[0], start[1] + d * direction[1])


@FUZZ
@given(st.tuples(coord, coord), st.floats(0.01, 5.0), st.one_of(st.none(), st.tuples(coord, coord, coord, coord)))
def test_default_arena_holds_home_or_refuses_clearly(home, half, explored):
    sane = finite(*home) and max(abs(home[0]), abs(home[1])) < 1e6  # a pose in a map, not 9e15 m
    try:
        arena = default_arena(home, half, explored)
    except ValueError:
        assert not sane  # only an absurd home has no arena (refused with a clear error)
        return
    assert arena.contains(*home) or not sane


def test_reach_with_a_zero_or_nan_direction_and_a_huge_distance_returns():
    arena = Arena.rectangle(-1.0, -1.0, 1.0, 1.0)
    assert arena.reach((0.0, 0.0), (0.0, 0.0), 1e9) == 0.0
    assert arena.reach((0.0, 0.0), (float("nan"), 0.0), 1e9) == 0.0
    assert arena.reach((0.0, 0.0), (1.0, 0.0), math.inf) <= 1.0


# ------------------------------------------------------------------------------ the controller's tick
class Scene:
    """Random inputs for a controller whose outside world never answers sensibly."""

    def __init__(self):
        self.goals = []
        self.logs = []
        self.ctl = MainController(
            Ports(
                get_gesture=lambda: "walk",
                generate_path=lambda c: (True, "ok", [(0.6, 0.0, 0.0), (-0.6, 0.0, math.pi), (0.0, 0.0, 0.0)],
                                         ["a", "b"]),
                set_position=lambda p: self.goals.append(("normal", p)) or (True, "ok"),
                set_body_pose=lambda r, p, h: True,
                pos_emergency=lambda on: None,
                pos_collision=lambda on: None,
                publish_estop=lambda on: None,
                publish=lambda c: None,
                log=lambda level, msg: self.logs.append((level, msg)),
                set_guarded_position=lambda x, y, v: self.goals.append(("guarded", (x, y, v))) or (True, "ok"),
                follow_path=lambda poses, v: self.goals.append(("path", poses[-1])) or (True, "ok"),
            ),
            avoid=AvoidParams(static_after=0.3, blocked_timeout=0.2, dodge=True, zone=ZONE, arena_half_size=2.0),
            start_timeout=0.5,
        )
        # The planner runs inside the tick here (the worker's thread is tested in test_planner_worker.py):
        # a planner that raises is then a logged give-up, caught below.
        self.ctl.avoidance.worker = PlannerWorker(inline=True)
        self.ctl.avoidance.budget = 0.5


@FUZZ
@given(st.lists(st.tuples(st.sampled_from(["pose", "zone", "blocking", "scan", "collision", "clear", "estop",
                                           "release", "status", "tick", "tick"]),
                          pose, reading, scan, st.sampled_from(["idle", "running", "collision", "??"]),
                          st.floats(0.0, 0.6)), max_size=30))
def test_the_tick_never_raises_and_no_behaviour_faults(steps):
    scene = Scene()
    ctl = scene.ctl
    ctl.start()
    ctl.set_emergency(False)
    t = 0.0
    for kind, robot, zone, pts, status, dt in steps:
        t += dt
        if kind == "pose":
            ctl.perception.on_pose(t, *robot)
        elif kind == "zone":
            ctl.on_lidar_state(t, sum(zone.points) >= 5, zone)
        elif kind == "blocking":
            ctl.perception.on_blocking_points(t, pts)
        elif kind == "scan":
            ctl.perception.on_scan_points(t, pts)
        elif kind in ("collision", "clear"):
            ctl.set_collision(kind == "collision")
        elif kind in ("estop", "release"):
            ctl.set_emergency(kind == "estop")
        elif kind == "status":
            ctl.on_pos_status(status)
        ctl.tick(t)
        assert ctl.faults == 0, "a behaviour raised in %s" % ctl.state.name
        assert ctl.state in State
    for _, goal in scene.goals:
        assert all(math.isfinite(v) for v in goal), scene.goals
    assert not [m for level, m in scene.logs if "planner crashed" in m], scene.logs
