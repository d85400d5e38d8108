"""The ROS-free decisions of active collision avoidance (issue 17).

Side indices FRONT=0, LEFT=1, BACK=2, RIGHT=3 are rbd_msgs/CollisionState's (tests/test_msgs.py
checks the message); zone sizes are rbd_lidar's defaults (front 0.70, left 0.35, back 0.55,
right 0.35 m, DESIGN §4).
"""

import math
import time

import numpy as np
import pytest

from rbd_controller.arena import Arena, default_arena
from rbd_controller.blocking import (
    CLEAR,
    MOVING,
    STATIC,
    UNKNOWN,
    BlockClassifier,
    is_low,
    near_fraction,
    top_beam_from,
)
from rbd_controller.detour import DetourPlanner, GridMap, dilate, distance_field
from rbd_controller.dodge import ApproachDetector, dodge_target
from rbd_controller.escape import BACK, FRONT, LEFT, RIGHT, ZoneReading, clear_by_margin, plan_escape

ZONE = (0.70, 0.35, 0.55, 0.35)  # FRONT, LEFT, BACK, RIGHT
BAND = (1.20, 0.55, 0.85, 0.55)  # + slowdown 0.5, 0.2, 0.3, 0.2
INF = math.inf


def box_face(x, y0, y1, n=40, noise=0.0, rng=None):
    ys = np.linspace(y0, y1, n)
    xs = np.full(n, x)
    if noise:
        xs = xs + rng.uniform(-noise, noise, n)
    return np.stack([xs, ys], axis=1)


def person(cx, cy, r=0.22, n=30):
    a = np.linspace(math.pi / 2, 3 * math.pi / 2, n)  # the half facing the robot at the origin
    return np.stack([cx + r * np.cos(a), cy + r * np.sin(a)], axis=1)


# ------------------------------------------------------------------------------ classification
def test_unmoved_box_becomes_static_after_static_after_with_noise():
    rng = np.random.default_rng(1)
    c = BlockClassifier(static_after=2.0)
    for i in range(15):
        c.update(0.1 * i, box_face(0.5, -0.2, 0.2, noise=0.03, rng=rng))
        assert c.classify() == UNKNOWN, i
    for i in range(15, 22):
        c.update(0.1 * i, box_face(0.5, -0.2, 0.2, noise=0.03, rng=rng))
    assert c.classify() == STATIC and "unmoved" in c.reason


#: rbd_lidar's OS1-32 beam table: altitudes from 20.55 deg up to 21.48 deg down.
BEAMS = np.linspace(20.5477, -21.4764, 32)
SENSOR_HEIGHT = 0.35  # the simulated OS1 above the floor [m]


def seen(distance, height, width=0.4, floor=0.10):
    """Points (x y z, LiDAR frame) of an upright face at distance whose top is height above the floor."""
    out = []
    for beam in np.radians(BEAMS):
        z = distance * math.tan(beam)
        if floor - SENSOR_HEIGHT <= z <= height - SENSOR_HEIGHT:
            out += [(distance, y, z) for y in np.linspace(-width / 2, width / 2, 9)]
    return np.array(out).reshape(-1, 3)


@pytest.mark.parametrize("distance", [0.45, 0.6, 0.8, 1.0, 1.3])
def test_a_bag_is_low_and_a_person_child_or_table_never_is(distance):
    top = top_beam_from(BEAMS.tolist())
    assert top == pytest.approx(math.radians(20.5477))
    assert is_low(seen(distance, 0.40), top)  # the 0.4 m box: its top seen, the beams above pass over
    for height in (1.75, 1.1, 0.75):  # a standing person, a child, a table's leg
        assert not is_low(seen(distance, height, width=0.2), top), height
    # Nothing seen, no beam table or a non-finite point: no low rule.
    assert not is_low(np.zeros((0, 3)), top)
    assert not is_low(seen(distance, 0.40), None) and top_beam_from([]) is None and top_beam_from("x") is None
    bad = seen(distance, 0.40)
    bad[0, 2] = float("nan")
    assert not is_low(bad, top)


def test_a_low_obstacle_is_static_after_low_after_a_tall_one_after_static_after_and_motion_wins():
    rng = np.random.default_rng(2)
    low, tall = BlockClassifier(static_after=5.0, low_after=1.5), BlockClassifier(static_after=5.0, low_after=1.5)
    for i in range(14):
        pts = box_face(0.5, -0.2, 0.2, noise=0.03, rng=rng)
        low.update(0.1 * i, pts, True)
        tall.update(0.1 * i, pts, False)
        assert low.classify() == UNKNOWN and tall.classify() == UNKNOWN, i
    for i in range(14, 17):
        pts = box_face(0.5, -0.2, 0.2, noise=0.03, rng=rng)
        low.update(0.1 * i, pts, True)
        tall.update(0.1 * i, pts, False)
    assert low.classify() == STATIC and low.low_match and "low obstacle" in low.reason
    assert tall.classify() == UNKNOWN and not tall.low_match
    # One scan in the window that was not low (a leg stepped in): no low verdict.
    mixed = BlockClassifier(static_after=5.0, low_after=1.5)
    for i in range(20):
        mixed.update(0.1 * i, box_face(0.5, -0.2, 0.2), i != 12)
    assert mixed.classify() == UNKNOWN
    # A low thing that moves (a dog) is moving at once and never static.
    dog = BlockClassifier(static_after=5.0, low_after=1.5)
    results = set()
    for i in range(30):
        dog.update(0.1 * i, person(0.6, -0.6 + 0.05 * i, r=0.15), True)
        results.add(dog.classify())
    assert MOVING in results and STATIC not in results
    with pytest.raises(ValueError):
        BlockClassifier(low_after=-1.0)


def test_walking_person_is_moving_and_never_static():
    c = BlockClassifier(static_after=2.0)
    seen = set()
    for i in range(40):
        c.update(0.1 * i, person(0.6, -0.6 + 0.1 * i))  # 1 m/s across the front
        seen.add(c.classify())
    assert MOVING in seen and STATIC not in seen


def test_person_stopping_becomes_static_only_static_after_later():
    c = BlockClassifier(static_after=2.0)
    for i in range(10):
        c.update(0.1 * i, person(0.6 + 0.05 * (10 - i), 0.0))  # approaching at 0.5 m/s
    assert c.classify() == MOVING
    t_stop = 1.0
    results = []
    for i in range(30):
        t = t_stop + 0.1 * i
        c.update(t, person(0.6, 0.0))
        results.append((t, c.classify()))
    first_static = next(t for t, r in results if r == STATIC)
    # Motion within the match radius (0.1 m, 0.2 s of this approach) counts as unmoved.
    assert t_stop + 2.0 - 0.3 <= first_static <= t_stop + 2.0 + 0.15


def test_points_on_the_map_are_static_after_map_confirm_and_clear_is_clear():
    c = BlockClassifier(static_after=5.0)  # rbd_controller's default ~static_after
    on_map = lambda x, y: abs(x - 0.45) < 0.06  # noqa: E731
    c.update(0.0, box_face(0.45, -0.3, 0.3))
    assert c.classify(on_map) == UNKNOWN  # one scan proves nothing about motion
    for i in range(1, 6):
        c.update(0.1 * i, box_face(0.45, -0.3, 0.3))
    assert c.classify(on_map) == STATIC and "map" in c.reason
    assert c.classify(lambda x, y: False) == UNKNOWN  # off the map: static_after (5 s) applies
    c.update(0.6, [])
    assert c.classify() == CLEAR


def box_outline(cx, cy, half=0.2, step=0.02):
    u = np.arange(-half, half + 1e-9, step)
    lo, hi = np.full(len(u), -half), np.full(len(u), half)
    sides = [(u, lo), (u, hi), (lo, u), (hi, u)]
    return np.concatenate([np.stack([cx + a, cy + b], 1) for a, b in sides])


def test_the_known_static_obstacle_is_static_after_map_confirm_whatever_part_of_it_is_seen():
    # Issue 27: going around a box already classified static, the robot stops at it again and sees
    # another part of it each time (its own motion changed what is in the zone). Without the known
    # obstacle that change reads as motion, and the stop starts from "unknown" (static_after, 5 s).
    known = box_outline(1.1, 0.0)
    walking = [box_face(0.9, -0.2, 0.2)] * 5 + [box_outline(1.1, 0.0)[:21]] * 2  # the part in the zone changes
    stopped = [box_face(1.3, -0.2, 0.0)] * 6  # then the robot stands at another face of it for 0.5 s
    plain, with_known = BlockClassifier(static_after=5.0), BlockClassifier(static_after=5.0)
    for i, pts in enumerate(walking + stopped):
        plain.update(0.1 * i, pts)
        with_known.update(0.1 * i, pts)
        if i == len(walking) + 2:
            assert with_known.classify(known=known) != STATIC  # 0.2 s of the stop: not yet
    assert plain.classify() == MOVING  # the visible part changed within static_after
    assert with_known.classify(known=known) == STATIC and with_known.known_match
    assert "static obstacle being avoided" in with_known.reason
    assert with_known.classify() == MOVING and not with_known.known_match  # it is the known set that decides


def test_the_known_obstacle_needs_map_confirm_of_scans_on_it():
    known = box_outline(1.1, 0.0)
    c = BlockClassifier(static_after=5.0, map_confirm=0.5)
    c.update(0.0, box_face(0.9, -0.2, 0.2))
    c.update(0.2, box_face(0.9, -0.2, 0.2))
    assert c.classify(known=known) == UNKNOWN  # observed 0.2 s
    c.update(0.3, box_face(0.75, -0.2, 0.2))  # off the box by 0.15 m (a person in front of it)
    c.update(0.6, box_face(0.9, -0.2, 0.2))
    assert c.classify(known=known) != STATIC
    for i in range(7, 13):
        c.update(0.1 * i, box_face(0.9, -0.2, 0.2))
    assert c.classify(known=known) == STATIC


@pytest.mark.parametrize("speed", [0.3, 0.7, 1.2])
def test_a_person_beside_the_known_obstacle_is_still_moving_and_never_static(speed):
    # A moving person still means stop and wait, at once, next to the box being avoided.
    known = box_outline(1.1, 0.0)
    c = BlockClassifier(static_after=5.0)
    seen = []
    for i in range(30):
        pts = np.concatenate([box_face(0.9, -0.2, 0.2), person(0.6, -0.8 + speed * 0.1 * i)])
        c.update(0.1 * i, pts)
        seen.append(c.classify(known=known))
    assert STATIC not in seen, c.reason
    assert MOVING in seen[:8], seen


def test_a_standing_person_where_the_box_is_not_is_not_the_known_obstacle():
    known = box_outline(1.1, 0.0)
    c = BlockClassifier(static_after=5.0)
    for i in range(20):
        c.update(0.1 * i, person(0.6, 0.3))
        assert c.classify(known=known) == UNKNOWN, i  # static_after applies: 5 s, as without a known box


@pytest.mark.parametrize("speed", [0.4, 0.7, 1.0])
def test_a_person_walking_where_the_map_is_occupied_is_never_static(speed):
    # The map is built live from the scans: the lab's visitor walks one loop over and over (0.7 m/s),
    # so her path is on it. Round 3's demo: "100 % of the blocking points are on the LiDAR map".
    c = BlockClassifier(static_after=5.0)
    seen = []
    for i in range(30):
        c.update(0.1 * i, person(0.6, -0.8 + speed * 0.1 * i))  # across the front, on mapped cells
        seen.append(c.classify(lambda x, y: True))
    assert STATIC not in seen, c.reason
    assert MOVING in seen[:8], seen  # within 0.8 s


def test_a_mapped_person_who_starts_walking_is_moving_at_once():
    c = BlockClassifier(static_after=5.0)
    for i in range(10):
        c.update(0.1 * i, person(0.6, 0.0))
    assert c.classify(lambda x, y: True) == STATIC  # stood still on a mapped spot for 1 s
    results = []
    for i in range(1, 6):
        c.update(0.9 + 0.1 * i, person(0.6, 0.07 * i))  # then walks at 0.7 m/s
        results.append(c.classify(lambda x, y: True))
    assert MOVING in results[:3], results


def test_new_blocker_after_a_clear_gap_starts_its_own_clock():
    c = BlockClassifier(static_after=2.0)
    for i in range(30):
        c.update(0.1 * i, box_face(0.5, -0.2, 0.2))
    for i in range(17):  # clear for 1.7 s (> max_gap 1.5 s)
        c.update(3.0 + 0.1 * i, [])
    c.update(4.7, box_face(0.6, 0.1, 0.3))
    assert c.classify() == UNKNOWN  # 0 s observed, although the history is longer


def test_stop_and_go_at_the_same_box_keeps_the_clock():
    c = BlockClassifier(static_after=2.0)
    t = 0.0
    for _ in range(4):  # 0.4 s blocked, 0.3 s clear (the zone shrinks when stopped), repeat
        for _ in range(4):
            c.update(t, box_face(0.5, -0.2, 0.2))
            t += 0.1
        for _ in range(3):
            c.update(t, [])
            t += 0.1
    c.update(t, box_face(0.5, -0.2, 0.2))
    assert c.classify() == STATIC, c.reason


def test_near_fraction():
    a = np.array([[0.0, 0.0], [1.0, 1.0]])
    assert near_fraction(a, np.array([[0.05, 0.0]]), 0.1) == 0.5
    assert near_fraction(np.zeros((0, 2)), a, 0.1) == 1.0


# ------------------------------------------------------------------------------ arena
def test_arena_contains_reach_and_segments():
    a = Arena([(0, 0), (2, 0), (2, 1), (0, 1)])
    assert a.contains(1.0, 0.5) and not a.contains(2.5, 0.5)
    assert a.reach((1.0, 0.5), (1.0, 0.0), 3.0) == pytest.approx(1.0, abs=0.021)
    assert a.reach((1.0, 0.5), (1.0, 0.0), 3.0, margin=0.2) == pytest.approx(0.8, abs=0.021)
    assert a.reach((3.0, 0.5), (1.0, 0.0), 1.0) == 0.0
    assert a.segment_inside((0.1, 0.1), (1.9, 0.9)) and not a.segment_inside((0.1, 0.1), (2.5, 0.9))
    concave = Arena([(0, 0), (2, 0), (2, 2), (1, 2), (1, 1), (0, 1)])  # an L
    assert not concave.contains(0.5, 1.5) and concave.contains(1.5, 1.5)
    for bad in ([(0, 0), (1, 1)], [(0, 0), (1, 1), (2, 2)], [(0, 0), (1, float("nan")), (0, 1)]):
        with pytest.raises(ValueError):
            Arena(bad)


def test_default_arena_is_cut_to_the_explored_map():
    square = default_arena((0.0, 0.0), 2.0)
    assert square.bounds() == (-2.0, -2.0, 2.0, 2.0)
    cut = default_arena((0.0, 0.0), 2.0, explored=(-3.0, -1.5, 5.0, 3.0), margin=0.3)
    assert cut.bounds() == pytest.approx((-2.0, -1.2, 2.0, 2.0))


# ------------------------------------------------------------------------------ detour
def box_points(cx, cy, half, step=0.02):
    pts = []
    for u in np.arange(-half, half + 1e-9, step):
        pts += [(cx + u, cy - half), (cx + u, cy + half), (cx - half, cy + u), (cx + half, cy + u)]
    return pts


def min_clearance(path_pts, obstacle_pts):
    obs = np.asarray(obstacle_pts)
    out = INF
    for a, b in zip(path_pts, path_pts[1:]):
        for u in np.linspace(0, 1, 50):
            p = np.array(a) + u * (np.array(b) - np.array(a))
            out = min(out, float(np.min(np.hypot(*(obs - p).T))))
    return out


def test_detour_goes_around_a_box_with_the_inflation_kept():
    planner = DetourPlanner(inflation=0.45, clearance=0.8)
    box = box_points(0.0, 0.0, 0.2)
    start, goal = (0.9, 0.0), (-1.2, 0.0)
    plan = planner.plan(start, goal, points=box)
    assert plan.ok, plan
    assert plan.waypoints[-1] == goal
    assert 2 <= len(plan.waypoints) <= 6
    assert plan.length < 2.0 * plan.direct
    assert min_clearance([start] + plan.waypoints, box) >= 0.45 - 0.05
    # The straight line would have hit the box: the detour really leaves the x axis.
    assert max(abs(p[1]) for p in plan.waypoints) > 0.4


def test_detour_uses_the_map_and_respects_the_arena():
    res = 0.05
    occ = np.zeros((80, 80), dtype=bool)  # 4 m x 4 m from (-2, -2)
    occ[:, 38:42] = True  # a wall at x = -0.1 .. 0.1 ...
    occ[60:, 38:42] = False  # ... with a gap at y >= 1.0
    grid = GridMap(occ, (-2.0, -2.0), res)
    planner = DetourPlanner(inflation=0.3, clearance=0.5)
    plan = planner.plan((1.0, 0.0), (-1.0, 0.0), grid=grid)
    assert plan.ok and max(p[1] for p in plan.waypoints) > 1.0 + 0.3 - 0.06  # through the gap
    fenced = planner.plan((1.0, 0.0), (-1.0, 0.0), grid=grid, arena=Arena.rectangle(-1.8, -1.8, 1.8, 1.0))
    assert not fenced.ok and "no path" in fenced.reason  # the gap lies outside the arena
    outside = planner.plan((1.0, 0.0), (-1.0, 1.5), grid=grid, arena=Arena.rectangle(-1.8, -1.8, 1.8, 1.0))
    assert not outside.ok and "arena" in outside.reason


def test_goal_inside_the_box_is_refused_with_a_reason():
    plan = DetourPlanner().plan((1.0, 0.0), (0.0, 0.1), points=box_points(0.0, 0.0, 0.2))
    assert not plan.ok and "goal blocked" in plan.reason


def test_start_inside_the_inflation_can_still_leave():
    box = box_points(0.0, 0.0, 0.2)
    plan = DetourPlanner(inflation=0.45).plan((0.55, 0.0), (-1.0, 0.0), points=box)  # 0.35 m from the face
    assert plan.ok, plan


def test_dilate_and_distance_field():
    m = np.zeros((11, 11), dtype=bool)
    m[5, 5] = True
    assert dilate(m, 2).sum() == 13  # disk of radius 2
    d = distance_field(m, 4)
    assert d[5, 5] == 0 and d[5, 8] == 3 and d[0, 0] == 4


def test_planning_time_is_interactive():
    box = box_points(0.0, 0.0, 0.2)
    t0 = time.process_time()
    plan = DetourPlanner().plan((0.9, 0.0), (-1.2, 0.0), points=box)
    assert plan.ok and time.process_time() - t0 < 2.0  # generous: the bench has the real figure


# ------------------------------------------------------------------------------ escape
def reading(points=(0, 0, 0, 0), dist=(INF, INF, INF, INF), **kw):
    return ZoneReading(points, dist, **kw)


def test_wall_ahead_backs_off_to_the_margin():
    r = reading((300, 0, 0, 0), (0.45, INF, INF, INF))
    esc, why = plan_escape(r, ZONE, (1.0, 2.0, math.pi / 2), margin=0.15)
    assert esc is not None, why
    assert esc.side == BACK
    assert esc.distance == pytest.approx(0.70 + 0.15 + 0.05 - 0.45)
    assert esc.target == pytest.approx((1.0, 2.0 - 0.45))  # backwards along a +y heading


def test_wall_ahead_and_behind_side_steps_to_the_freer_side():
    r = reading((300, 0, 200, 0), (0.45, 0.50, 0.40, INF))
    esc, _ = plan_escape(r, ZONE, (0.0, 0.0, 0.0))
    assert esc.side == RIGHT and esc.distance == pytest.approx(0.3)


def test_wedged_in_every_direction_and_invalid_readings():
    r = reading((300, 100, 200, 100), (0.45, 0.3, 0.4, 0.3))
    esc, why = plan_escape(r, ZONE, (0.0, 0.0, 0.0))
    assert esc is None and why.startswith("wedged")
    esc, why = plan_escape(reading((300, 0, 0, 0), (0.45, INF, INF, INF), stale=True), ZONE, (0, 0, 0))
    assert esc is None and "stale" in why


def test_escape_distance_is_limited_by_the_arena_and_the_room_behind():
    r = reading((300, 0, 0, 0), (0.30, INF, 0.80, INF))  # something 0.80 m behind
    esc, _ = plan_escape(r, ZONE, (0.0, 0.0, 0.0), margin=0.15)
    assert esc.side == BACK and esc.distance == pytest.approx(0.80 - 0.55 - 0.15)
    fenced = Arena.rectangle(-0.3, -2, 2, 2)
    esc, _ = plan_escape(reading((300, 0, 0, 0), (0.30, INF, INF, INF)), ZONE, (0.0, 0.0, 0.0), arena=fenced)
    assert esc.distance == pytest.approx(0.2, abs=0.021)


def test_escape_backs_off_as_far_as_the_turn_room_asks_where_there_is_room():
    # Issue 27: beside the box the detour began with a turn on the spot at 7 deg/s (the 0.15 m margin
    # left the box inside a faster turn's swept circle); the escape now aims for the turn's room.
    room = (0.30, 0.55, 0.28, 0.55)
    r = reading((300, 0, 0, 0), (0.80, INF, INF, INF))  # the box's face 0.80 m ahead: clear by 0.10 m only
    esc, why = plan_escape(r, ZONE, (0.0, 0.0, 0.0), margin=0.15, room=room)
    assert esc is not None and esc.side == BACK, why
    assert esc.distance == pytest.approx(0.70 + 0.30 + 0.05 - 0.80)
    plain, _ = plan_escape(r, ZONE, (0.0, 0.0, 0.0), margin=0.15)
    assert plain.distance == pytest.approx(0.70 + 0.15 + 0.05 - 0.80) and plain.distance < esc.distance
    # Never beyond the free space behind (kept clear by the margin), max_distance or the arena.
    esc, _ = plan_escape(reading((300, 0, 0, 0), (0.80, INF, 0.85, INF)), ZONE, (0.0, 0.0, 0.0), margin=0.15,
                         room=room)
    assert esc.distance == pytest.approx(0.85 - 0.55 - 0.15)
    esc, _ = plan_escape(reading((300, 0, 0, 0), (0.30, INF, INF, INF)), ZONE, (0.0, 0.0, 0.0), margin=0.15,
                         max_distance=0.6, room=room)
    assert esc.distance == pytest.approx(0.6)
    # A room below the margin changes nothing; an already clear zone is not escaped from.
    esc, _ = plan_escape(r, ZONE, (0.0, 0.0, 0.0), margin=0.15, room=(0.0, 0.0, 0.0, 0.0))
    assert esc.distance == pytest.approx(plain.distance)
    esc, why = plan_escape(reading(dist=(0.90, INF, INF, INF)), ZONE, (0.0, 0.0, 0.0), margin=0.15, room=room)
    assert esc is None and "already clear" in why


def test_clear_by_margin():
    assert clear_by_margin(reading(dist=(0.9, INF, INF, INF)), ZONE, 5, 0.15)
    assert not clear_by_margin(reading(dist=(0.8, INF, INF, INF)), ZONE, 5, 0.15)
    assert not clear_by_margin(reading(stale=True), ZONE, 5, 0.15)


# ------------------------------------------------------------------------------ dodge
def test_approach_is_detected_standing_things_are_not():
    det = ApproachDetector(BAND, approach_speed=0.15, window=0.4)
    sides = []
    for i in range(10):  # a wall 0.9 m ahead: inside the front band, not approaching
        sides += det.update(0.1 * i, (0.9, INF, INF, INF))
    assert sides == []
    det = ApproachDetector(BAND)
    hits = []
    for i in range(12):  # a visitor at 1.0 m/s from 1.6 m
        hits.append(det.update(0.1 * i, (1.6 - 0.1 * i, INF, INF, INF)))
    first = next(i for i, h in enumerate(hits) if h)
    assert hits[first] == [FRONT] and 1.6 - 0.1 * first < 1.2  # only once inside the band
    assert det.quiet_for(1.1) == pytest.approx(0.0)


def test_dodge_target_stays_within_dodge_max_and_the_arena():
    home = (0.0, 0.0)
    target, _ = dodge_target(home, (0.0, 0.0, 0.0), FRONT, step=0.3, max_offset=0.5)
    assert target == pytest.approx((-0.3, 0.0))
    target, _ = dodge_target(home, (-0.3, 0.0, 0.0), FRONT, step=0.3, max_offset=0.5)
    assert target == pytest.approx((-0.5, 0.0))
    none, why = dodge_target(home, (-0.5, 0.0, 0.0), FRONT, step=0.3, max_offset=0.5)
    assert none is None and "no room" in why
    target, _ = dodge_target(home, (0.0, 0.0, math.pi / 2), LEFT, step=0.3, max_offset=0.5)
    assert target == pytest.approx((0.3, 0.0))  # facing +y, approached from its left (-x): step to +x
    fenced, _ = dodge_target(home, (0.0, 0.0, 0.0), FRONT, arena=Arena.rectangle(-0.25, -1, 1, 1), arena_margin=0.1)
    assert fenced == pytest.approx((-0.14, 0.0), abs=0.021)
    assert dodge_target(home, (0.0, 0.0, 0.0), BACK)[0] == pytest.approx((0.3, 0.0))
    assert dodge_target(home, (0.0, 0.0, 0.0), RIGHT)[0] == pytest.approx((0.0, 0.3))
