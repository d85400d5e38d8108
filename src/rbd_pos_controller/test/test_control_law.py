import math

import pytest

from rbd_pos_controller.control_law import (
    Errors,
    Gains,
    hold_command,
    linear_command,
    rotation_command,
    saturate,
    wrap_angle,
)

TABLE2 = Gains()


def test_table2_defaults():
    g = Gains()
    assert (g.k_x, g.k_y, g.k_alpha) == (2.5, 2.0, 1.0)
    assert (g.max_vx, g.max_vy) == (0.3, 0.12)
    assert g.max_wz == pytest.approx(math.radians(36.0))


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf"), "1", True])
def test_gains_reject_bad_values(bad):
    with pytest.raises(ValueError):
        Gains(k_x=bad)


def test_geometric_variables():
    # robot at (1, 1) facing +y, goal at (2, 1) facing -x
    e = Errors(1.0, 1.0, math.pi / 2, 2.0, 1.0, math.pi)
    assert e.rho == pytest.approx(1.0)
    assert e.alpha == pytest.approx(0.0)
    assert e.gamma == pytest.approx(-math.pi / 2)
    assert e.delta == pytest.approx(math.pi / 2)
    assert (e.ex_robot, e.ey_robot) == pytest.approx((e.rho * math.cos(e.gamma), e.rho * math.sin(e.gamma)))


def test_linear_law_small_error_is_eq1():
    e = Errors(0.0, 0.0, 0.0, 0.04, 0.02, 0.0)
    vx, vy = linear_command(e, TABLE2)
    assert vx == pytest.approx(2.5 * e.rho * math.cos(e.gamma))
    assert vy == pytest.approx(2.0 * e.rho * math.sin(e.gamma))


def test_linear_law_saturates_and_keeps_direction():
    e = Errors(0.0, 0.0, 0.0, 2.0, 0.2, 0.0)
    vx, vy = linear_command(e, TABLE2, keep_direction=True)
    assert vx == pytest.approx(0.3)
    assert abs(vy) <= 0.12 + 1e-12
    # direction of the velocity equals the direction of k-weighted error
    assert vy / vx == pytest.approx((2.0 * 0.2) / (2.5 * 2.0))


def test_linear_law_independent_saturation():
    e = Errors(0.0, 0.0, 0.0, 2.0, 1.0, 0.0)
    assert linear_command(e, TABLE2, keep_direction=False) == pytest.approx((0.3, 0.12))


def test_linear_law_backwards_and_sideways():
    e = Errors(0.0, 0.0, 0.0, -0.01, -0.01, 0.0)
    vx, vy = linear_command(e, TABLE2)
    assert vx < 0 and vy < 0


def test_rotation_law_and_saturation():
    assert rotation_command(0.1, TABLE2) == pytest.approx(0.1)
    assert rotation_command(3.0, TABLE2) == pytest.approx(math.radians(36.0))
    assert rotation_command(-3.0, TABLE2) == pytest.approx(-math.radians(36.0))
    # errors are wrapped: +350 deg is -10 deg
    assert rotation_command(math.radians(350.0), Gains(k_alpha=1.0)) == pytest.approx(math.radians(-10.0))


def test_hold_command_axes():
    e = Errors(0.0, 0.0, 0.0, 0.01, 0.02, 0.0)
    assert hold_command(e, 5.0, 0.2, use_x=False, use_y=True) == pytest.approx((0.0, 0.1))
    assert hold_command(e, 5.0, 0.2, use_x=True, use_y=True) == pytest.approx((0.05, 0.1))
    assert hold_command(e, 50.0, 0.2, use_x=True, use_y=False) == pytest.approx((0.2, 0.0))


def test_helpers():
    assert wrap_angle(3 * math.pi) == pytest.approx(-math.pi)
    assert wrap_angle(-0.5) == pytest.approx(-0.5)
    assert saturate(5.0, 1.0) == 1.0 and saturate(-5.0, 1.0) == -1.0 and saturate(0.5, 1.0) == 0.5
