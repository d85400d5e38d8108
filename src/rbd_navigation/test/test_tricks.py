import math
import os

import pytest
import yaml

from rbd_navigation.tricks import TrickError, expand, parse_step, parse_tricks

CONFIG = os.path.join(os.path.dirname(__file__), "..", "config", "tricks.yaml")


def load_default():
    with open(CONFIG) as fh:
        return parse_tricks(yaml.safe_load(fh))


def test_default_file_has_the_four_commands_with_names():
    tricks = load_default()
    assert {"walk", "spin", "wiggle", "lie_down"} <= set(tricks)
    for steps in tricks.values():
        assert all(s.name for s in steps)


def test_walk_from_origin_matches_design():
    goals = expand(load_default()["walk"], 0.0, 0.0, 0.0)
    assert (goals[0].x, goals[0].y, goals[0].yaw) == pytest.approx((0.6, 0.0, 0.0))
    assert (goals[1].x, goals[1].y) == pytest.approx((-0.6, 0.0))
    assert abs(abs(goals[1].yaw) - math.pi) < 1e-9  # facing back
    assert (goals[-1].x, goals[-1].y, goals[-1].yaw) == pytest.approx((0.0, 0.0, 0.0))


def test_walk_is_relative_to_robot_pose():
    goals = expand(load_default()["walk"], 2.0, 1.0, math.pi / 2)
    # "forward 0.6 m" while facing +y ends at (2.0, 1.6)
    assert (goals[0].x, goals[0].y) == pytest.approx((2.0, 1.6))
    assert goals[0].yaw == pytest.approx(math.pi / 2)
    assert (goals[1].x, goals[1].y) == pytest.approx((2.0, 0.4))
    assert goals[1].yaw == pytest.approx(-math.pi / 2)
    assert (goals[2].x, goals[2].y) == pytest.approx((2.0, 1.0))


def test_spin_turns_half_and_back_in_place():
    goals = expand(load_default()["spin"], 1.0, -1.0, 0.5)
    assert [(g.x, g.y) for g in goals] == [pytest.approx((1.0, -1.0))] * 2
    assert math.cos(goals[0].yaw - 0.5) == pytest.approx(-1.0)
    assert goals[1].yaw == pytest.approx(0.5)


def test_wiggle_and_lie_down_are_body_poses_only():
    tricks = load_default()
    wiggle = expand(tricks["wiggle"], 0.3, 0.2, 1.0)
    assert [g.roll for g in wiggle] == pytest.approx([-0.3, 0.0, 0.3, 0.0])
    assert all((g.x, g.y, g.yaw) == pytest.approx((0.3, 0.2, 1.0)) for g in wiggle)
    lie = expand(tricks["lie_down"], 0.0, 0.0, 0.0)
    assert [g.body_height for g in lie] == pytest.approx([-0.16, 0.0])


@pytest.mark.parametrize(
    "data, fragment",
    [
        (None, "non-empty mapping"),
        ({"tricks": {}}, "non-empty mapping"),
        ({"tricks": {"walk": []}}, "non-empty list"),
        ({"tricks": {"walk": "forward"}}, "non-empty list"),
        ({"tricks": {"walk": [{"x": 1.0}]}}, "name"),
        ({"tricks": {"walk": [{"name": "", "x": 1.0}]}}, "name"),
        ({"tricks": {"walk": [{"name": "a", "z": 1.0}]}}, "unknown key"),
        ({"tricks": {"walk": [{"name": "a", "x": "far"}]}}, "must be a number"),
        ({"tricks": {"walk": [{"name": "a", "x": True}]}}, "must be a number"),
        ({"tricks": {"walk": [{"name": "a", "x": float("nan")}]}}, "finite"),
        ({"tricks": {"walk": [{"name": "a", "roll": 1.0}]}}, "limit"),
        ({"tricks": {"walk": [{"name": "a", "body_height": -0.3}]}}, "range"),
        ({"tricks": {"walk": [{"name": "a", "x": 10.0}]}}, "exceeds"),
        ({"tricks": {" walk": [{"name": "a"}]}}, "trick names"),
        ({"tricks": {"walk": ["forward"]}}, "mapping"),
    ],
)
def test_invalid_files_fail_with_clear_message(data, fragment):
    with pytest.raises(TrickError) as err:
        parse_tricks(data)
    assert fragment in str(err.value)


def test_error_message_names_the_step():
    with pytest.raises(TrickError, match=r"tricks\.dance\[1\]\.pitch"):
        parse_tricks({"dance": [{"name": "a"}, {"name": "b", "pitch": 2.0}]})


def test_defaults_are_zero():
    step = parse_step({"name": "stay"}, "s")
    assert (step.x, step.y, step.yaw, step.roll, step.pitch, step.body_height) == (0.0,) * 6


def test_expand_rejects_nan_pose():
    steps = load_default()["walk"]
    with pytest.raises(TrickError):
        expand(steps, float("nan"), 0.0, 0.0)

