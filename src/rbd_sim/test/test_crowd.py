"""The random crowd (rbd_sim.crowd) and the world file's crowd section."""

import math
import os

import pytest

from rbd_sim.crowd import CROWD_MAX_SPEED, crowd_people, segment_distance
from rbd_sim.shapes import Person, WorldError
from rbd_sim.world_file import load_world, resolve_world_path, world_from_dict

WORLDS_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "worlds")



def _min_distance_to_origin(person, seconds=120.0, step=0.05):
    t, best = 0.0, math.inf
    while t < seconds:
        x, y = person.position(t)
        best = min(best, math.hypot(x, y))
        t += step
    return best


def test_crowd_world_loads_and_keeps_out_of_the_trick_area():
    w = load_world(resolve_world_path("crowd", WORLDS_DIR))
    crowd = [p for p in w.people if p.name.startswith("crowd")]
    assert len(crowd) == 12
    for p in crowd:
        assert 0.0 < p.speed <= CROWD_MAX_SPEED
        # Sampled over two minutes: the body never enters the 1.5 m ring (tricks reach 0.9 m).
        assert _min_distance_to_origin(p) >= 1.5 - 1e-6, p.name
        for a, b in zip(p.points[:-1], p.points[1:]):
            assert segment_distance(a, b, (0.0, 0.0)) >= 1.5 - 1e-9
            assert max(math.hypot(*a), math.hypot(*b)) <= 5.0 + 1e-9


def test_crowd_is_reproducible_and_seed_dependent():
    a = crowd_people(8, seed=3)
    b = crowd_people(8, seed=3)
    c = crowd_people(8, seed=4)
    assert [p.points for p in a] == [p.points for p in b]
    assert [p.position(17.3) for p in a] == [p.position(17.3) for p in b]
    assert [p.points for p in a] != [p.points for p in c]


def test_crowd_people_move_and_get_close():
    people = crowd_people(20, seed=7, inner_radius=1.5, outer_radius=4.0)
    speeds = [p.speed for p in people]
    assert min(speeds) >= 0.5 and max(speeds) <= 1.5
    assert len({p.mode for p in people}) == 2  # loops and there-and-back paths
    for p in people:
        moved = math.hypot(p.position(0.0)[0] - p.position(1.0)[0], p.position(0.0)[1] - p.position(1.0)[1])
        assert 0.0 < moved <= p.speed + 1e-9
    # Someone comes within 0.3 m of the keep-out ring (through a walking robot's LiDAR zone).
    assert min(_min_distance_to_origin(p, 60.0) for p in people) < 1.8


def test_crowd_off_centre_and_mixed_with_scripted_people():
    w = world_from_dict(
        {
            "people": [{"name": "alice", "path": [[5, 5]], "mode": "stand"}],
            "crowd": {"count": 3, "seed": 1, "center": [10.0, -2.0], "inner_radius": 2.0, "outer_radius": 3.0},
        }
    )
    assert [p.name for p in w.people] == ["alice", "crowd0", "crowd1", "crowd2"]
    for p in w.people[1:]:
        assert _min_distance_to_origin(
            Person(p.name, [(x - 10.0, y + 2.0) for x, y in p.points], p.speed, "stand"), 1.0
        ) >= 2.0 - 1e-6


@pytest.mark.parametrize(
    "crowd, match",
    [
        ({"seed": 1}, "missing required key.*count"),
        ({"count": 3, "speed": 1.0}, "unknown key.*speed"),
        ({"count": 3, "max_speed": 2.0}, "max_speed <= 1.5"),
        ({"count": 3, "min_speed": 1.2, "max_speed": 1.0}, "min_speed <= max_speed"),
        ({"count": 3, "inner_radius": 3.0, "outer_radius": 2.0}, "inner_radius < outer_radius"),
        ({"count": 3, "inner_radius": 2.0, "outer_radius": 2.1}, "too narrow"),
        ({"count": -1}, "count must be in"),
        ({"count": 2.5}, "count: expected an integer"),
        ({"count": 3, "waypoints": 1}, "waypoints must be"),
        ([3], "must be a mapping"),
    ],
)
def test_bad_crowd_gives_clear_errors(crowd, match):
    with pytest.raises(WorldError, match=match):
        world_from_dict({"crowd": crowd})


def test_crowd_name_clash_is_an_error():
    with pytest.raises(WorldError, match="already used"):
        world_from_dict({"people": [{"name": "crowd0", "path": [[5, 5]]}], "crowd": {"count": 1}})
