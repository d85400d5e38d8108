"""rbd_geometry.rotation against hand-worked rotations (truth from geometry, not from the module)."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from rbd_geometry import rotation as rot

S = math.sqrt(0.5)


def test_quarter_turn_about_z_has_yaw_pi_over_2_and_maps_x_to_y():
    q = (0.0, 0.0, S, S)
    assert rot.quat_to_rpy(q) == pytest.approx((0.0, 0.0, math.pi / 2))
    assert rot.yaw_of(SimpleNamespace(x=0.0, y=0.0, z=S, w=S)) == pytest.approx(math.pi / 2)
    assert rot.quat_to_matrix(q).dot([1.0, 0.0, 0.0]) == pytest.approx([0.0, 1.0, 0.0])


def test_pitch_down_by_half_a_radian_tips_the_x_axis_below_the_horizon():
    q = rot.rpy_to_quat(0.0, 0.5, 0.0)
    assert q == pytest.approx((0.0, math.sin(0.25), 0.0, math.cos(0.25)))
    assert rot.quat_to_matrix(q).dot([1.0, 0.0, 0.0]) == pytest.approx([math.cos(0.5), 0.0, -math.sin(0.5)])


def test_fixed_axis_order_is_roll_then_pitch_then_yaw():
    # Rz(pi/2) Ry(0) Rx(pi/2): y goes to z (roll), then z stays z under the yaw.
    m = rot.rpy_to_matrix(math.pi / 2, 0.0, math.pi / 2)
    assert m.dot([0.0, 1.0, 0.0]) == pytest.approx([0.0, 0.0, 1.0], abs=1e-12)
    assert m.dot([1.0, 0.0, 0.0]) == pytest.approx([0.0, 1.0, 0.0], abs=1e-12)


@pytest.mark.parametrize("rpy", [(0.1, -0.2, 3.0), (-1.2, 0.7, -2.5), (0.0, 0.0, -math.pi / 3)])
def test_round_trips(rpy):
    q = rot.rpy_to_quat(*rpy)
    assert rot.quat_to_rpy(q) == pytest.approx(rpy)
    m = rot.rpy_to_matrix(*rpy)
    assert rot.matrix_to_rpy(m) == pytest.approx(rpy)
    assert rot.quat_to_matrix(q) == pytest.approx(m)
    back = rot.matrix_to_quat(m)
    assert abs(float(np.dot(back, q))) == pytest.approx(1.0)  # q and -q are one rotation


def test_yaw_to_quat_and_a_non_unit_quaternion_is_normalised():
    assert rot.yaw_to_quat(math.pi) == pytest.approx((0.0, 0.0, 1.0, 0.0), abs=1e-12)
    assert rot.yaw_of((0.0, 0.0, 3.0 * S, 3.0 * S)) == pytest.approx(math.pi / 2)


@pytest.mark.parametrize("bad", [(0.0, 0.0, 0.0, 0.0), (float("nan"), 0.0, 0.0, 1.0), (1.0, 2.0), ("a", 0, 0, 1)])
def test_bad_quaternions_raise_value_error(bad):
    with pytest.raises(ValueError):
        rot.quat_to_rpy(bad)


def test_yaw_or_nan_is_nan_exactly_where_yaw_of_raises():
    assert rot.yaw_or_nan(SimpleNamespace(x=0.0, y=0.0, z=S, w=S)) == pytest.approx(math.pi / 2)
    for bad in ((0.0, 0.0, 0.0, 0.0), (0.0, 0.0, float("inf"), 1.0), SimpleNamespace(x=0, y=0, z=0, w=float("nan"))):
        with pytest.raises(ValueError):
            rot.yaw_of(bad)
        assert math.isnan(rot.yaw_or_nan(bad))


def test_wrap_angle():
    assert rot.wrap_angle(3.0 * math.pi / 2) == pytest.approx(-math.pi / 2)
    assert rot.wrap_angle(-math.pi) == pytest.approx(-math.pi)
    assert rot.wrap_angle(0.25) == pytest.approx(0.25)


def _scipy_matrix(r):
    return r.as_matrix() if hasattr(r, "as_matrix") else r.as_dcm()


def test_every_conversion_agrees_with_scipys_rotation():
    # scipy's Rotation is the independent truth for the closed forms of the module
    from scipy.spatial.transform import Rotation

    rng = np.random.RandomState(30)
    for _ in range(200):
        rpy = (rng.uniform(-math.pi, math.pi), rng.uniform(-1.5, 1.5), rng.uniform(-math.pi, math.pi))
        ref = Rotation.from_euler("xyz", rpy)
        q = ref.as_quat()
        assert abs(float(np.dot(rot.rpy_to_quat(*rpy), q))) == pytest.approx(1.0)
        assert rot.quat_to_rpy(tuple(q)) == pytest.approx(tuple(ref.as_euler("xyz")), abs=1e-9)
        assert rot.quat_to_matrix(tuple(q)) == pytest.approx(_scipy_matrix(ref), abs=1e-12)
        assert rot.rpy_to_matrix(*rpy) == pytest.approx(_scipy_matrix(ref), abs=1e-12)
        assert rot.matrix_to_rpy(_scipy_matrix(ref)) == pytest.approx(rpy, abs=1e-9)
        assert abs(float(np.dot(rot.matrix_to_quat(_scipy_matrix(ref)), q))) == pytest.approx(1.0)
        yaw = rpy[2]
        assert rot.yaw_to_quat(yaw) == pytest.approx(tuple(Rotation.from_euler("z", yaw).as_quat()), abs=1e-12)
