"""World files: loading, validation errors, people on scripted paths, run-time obstacles."""

import math
import os

import pytest

from rbd_sim.shapes import Person, WorldError
from rbd_sim.world_file import load_world, resolve_world_path, world_from_dict

WORLDS_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "worlds")


@pytest.mark.parametrize("name", ["lab", "fair"])
def test_shipped_worlds_load(name):
    w = load_world(resolve_world_path(name, WORLDS_DIR))
    assert w.name == name
    assert len(w.boxes) >= 5
    assert len(w.people) >= 2
    # Nothing within 1.9 m of the start pose at any time in the first minute (tricks + zone fit).
    for t in range(0, 60):
        for c in w.all_cylinders(float(t)):
            assert math.hypot(c.cx, c.cy) - c.radius > 1.9, (name, c.name, t)
    for b in w.boxes:
        c, s = math.cos(b.yaw), math.sin(b.yaw)
        u, v = c * -b.cx + s * -b.cy, -s * -b.cx + c * -b.cy  # origin in the box frame
        gap = math.hypot(max(abs(u) - b.hx, 0.0), max(abs(v) - b.hy, 0.0))
        assert gap > 1.5, (name, b.name, gap)


def test_fair_is_crowded():
    assert len(load_world(resolve_world_path("fair", WORLDS_DIR)).people) >= 10


def test_unknown_world_name_lists_known():
    with pytest.raises(WorldError, match="known worlds: .*lab"):
        resolve_world_path("nope", WORLDS_DIR)


@pytest.mark.parametrize(
    "data, match",
    [
        ({"wals": []}, "unknown top-level key.*wals"),
        ({"walls": [{"from": [0, 0], "to": [1, 0], "heigth": 2}]}, r"walls\[0\].*unknown key.*heigth"),
        ({"boxes": [{"center": [0, 0]}]}, r"boxes\[0\].*missing required key.*size"),
        ({"boxes": [{"center": [0, 0], "size": [1, 1]}]}, r"size: expected \[lx, ly, lz\]"),
        ({"cylinders": [{"center": [0, 0], "radius": -1, "height": 1}]}, "radius.*out of range"),
        ({"people": [{"name": "p", "path": [[0, 0]], "mode": "dance"}]}, "mode.*dance"),
        ({"people": [{"name": "p", "path": []}]}, "non-empty list"),
        ({"people": [{"name": "p", "path": [[0, "a"]]}]}, "finite number"),
        ({"tables": [{"center": [0, 0], "size": [1, 1], "height": "tall"}]}, "height.*finite number"),
        (
            {
                "boxes": [
                    {"name": "a", "center": [0, 0], "size": [1, 1, 1]},
                    {"name": "a", "center": [2, 0], "size": [1, 1, 1]},
                ]
            },
            "duplicate name",
        ),
        ({"floor": {"height": 0}}, "floor: unknown key"),
        ([1, 2], "top level must be a mapping"),
        ({"walls": [{"from": [0, 0], "to": [0, 0]}]}, "zero length"),
    ],
)
def test_bad_entries_give_clear_errors(data, match):
    with pytest.raises(WorldError, match=match):
        world_from_dict(data, "test.yaml")


def test_bad_yaml_file(tmp_path):
    p = tmp_path / "broken.yaml"
    p.write_text("walls: [unclosed\n")
    with pytest.raises(WorldError, match="cannot read world file"):
        load_world(str(p))


def test_table_is_top_and_four_legs():
    w = world_from_dict({"tables": [{"name": "t", "center": [1, 2], "size": [1.2, 0.6], "height": 0.7}]})
    assert [b.name for b in w.boxes] == ["t/top", "t/leg0", "t/leg1", "t/leg2", "t/leg3"]
    top = w.boxes[0]
    assert top.z1 == pytest.approx(0.7) and top.z0 == pytest.approx(0.66)
    assert all(b.z0 == 0.0 and b.z1 == pytest.approx(0.66) for b in w.boxes[1:])
    xs = sorted(round(b.cx, 3) for b in w.boxes[1:])
    assert xs == [0.425, 0.425, 1.575, 1.575]


def test_wall_from_segment():
    w = world_from_dict({"walls": [{"from": [0, 0], "to": [0, 4], "thickness": 0.2, "height": 2}]})
    b = w.boxes[0]
    assert (b.cx, b.cy, b.hx, b.hy) == pytest.approx((0, 2, 2, 0.1))
    assert b.yaw == pytest.approx(math.pi / 2)


def test_person_paths():
    loop = Person("a", [(0, 0), (2, 0), (2, 2)], speed=1.0, mode="loop")
    assert loop.length == pytest.approx(4 + math.sqrt(8))
    assert loop.position(1.0) == pytest.approx((1.0, 0.0))
    assert loop.position(3.0) == pytest.approx((2.0, 1.0))
    assert loop.position(loop.length) == pytest.approx((0.0, 0.0), abs=1e-9)  # back at the start
    pp = Person("b", [(0, 0), (3, 0)], speed=1.5, mode="pingpong")
    assert pp.position(1.0) == pytest.approx((1.5, 0))
    assert pp.position(3.0) == pytest.approx((1.5, 0))  # on the way back
    assert pp.position(4.0) == pytest.approx((0.0, 0))
    assert Person("c", [(1, 2), (5, 5)], mode="stand").position(100.0) == (1.0, 2.0)
    ph = Person("d", [(0, 0), (4, 0)], speed=1.0, mode="pingpong", phase=1.0)
    assert ph.position(0.0) == pytest.approx((1.0, 0.0))


def test_people_move_deterministically():
    a = load_world(resolve_world_path("lab", WORLDS_DIR))
    b = load_world(resolve_world_path("lab", WORLDS_DIR))
    for t in (0.0, 1.3, 17.9):
        assert [(c.cx, c.cy) for c in a.dynamic_cylinders(t)] == [(c.cx, c.cy) for c in b.dynamic_cylinders(t)]
    assert (
        a.dynamic_cylinders(0.0)[0].cx != a.dynamic_cylinders(2.0)[0].cx
        or a.dynamic_cylinders(0.0)[0].cy != a.dynamic_cylinders(2.0)[0].cy
    )


def test_place_move_remove():
    w = world_from_dict({})
    assert w.place("p", 1.0, 2.0, 0.3, 1.7) == "added"
    assert w.place("p", -1.0, 0.5, 0.3, 1.7) == "moved"
    (c,) = w.all_cylinders(0.0)
    assert (c.cx, c.cy, c.radius, c.z1, c.kind) == (-1.0, 0.5, 0.3, 1.7, "placed")
    w.remove("p")
    assert w.all_cylinders(0.0) == []
    with pytest.raises(WorldError, match="no such obstacle"):
        w.remove("p")


@pytest.mark.parametrize(
    "args, match",
    [
        (("", 0, 0, 0.3, 1), "name"),
        (("p", float("nan"), 0, 0.3, 1), "finite"),
        (("p", 0, 0, 0.0, 1), "> 0"),
        (("p", 0, 0, 0.3, -1), "> 0"),
        (("p", 0, 0, 50.0, 1), "radius <= 5"),
    ],
)
def test_place_rejects_bad_values(args, match):
    w = world_from_dict({})
    with pytest.raises(WorldError, match=match):
        w.place(*args)
    assert w.placed == {}


# -- randomized crowd (issue 10 crowd soak) ---------------------------------------------------
def test_place_box_add_move_remove_and_errors():
    from rbd_sim.world import World

    w = World()
    assert w.place_box("bag", 1.0, 0.0, 0.3, 0.4, 0.4, 0.4) == "added"
    assert w.place_box("bag", 2.0, 0.5, 0.0, 0.4, 0.4, 0.4) == "moved"
    (b,) = [b for b in w.all_boxes() if b.name == "bag"]
    assert (b.cx, b.cy, b.hx, b.hy, b.z1 - b.z0) == (2.0, 0.5, 0.2, 0.2, 0.4)
    for bad in (("", 0, 0, 0, 1, 1, 1), ("b", float("nan"), 0, 0, 1, 1, 1), ("b", 0, 0, 0, 0.0, 1, 1),
                ("b", 0, 0, 0, 1, 1, 11.0), ("b", 0, 0, 0, 21.0, 1, 1)):
        with pytest.raises(WorldError):
            w.place_box(*bad)
    w.remove("bag")
    assert w.all_boxes() == list(w.boxes)
    with pytest.raises(WorldError, match="no such obstacle"):
        w.remove("bag")
