"""rbd_geometry.goal.Goal: the shared goal pose keeps what it is given and says it in logs."""

from rbd_geometry.goal import Goal


def test_a_goal_defaults_to_a_level_neutral_unnamed_body():
    g = Goal(1.0, -2.0, 0.5)
    assert (g.x, g.y, g.yaw, g.roll, g.pitch, g.body_height, g.name) == (1.0, -2.0, 0.5, 0.0, 0.0, 0.0, "")
    assert repr(g) == "Goal(x=1.000, y=-2.000, yaw=0.500, roll=0.000, pitch=0.000, body_height=0.000)"


def test_a_named_goal_says_its_name_first_and_holds_no_other_attribute():
    g = Goal(0.0, 0.0, 0.0, roll=0.1, pitch=-0.2, body_height=-0.05, name="bow")
    assert repr(g) == "Goal('bow', x=0.000, y=0.000, yaw=0.000, roll=0.100, pitch=-0.200, body_height=-0.050)"
    try:
        g.speed = 1.0  # type: ignore[attr-defined]
    except AttributeError:
        pass
    else:
        raise AssertionError("Goal has __slots__: a typo'd attribute must fail")
