"""HighState -> odometry values: quaternion reordering and field mapping."""

import math

import pytest

from rbd_a1_driver import unitree_layout as ul
from rbd_a1_driver.state_conv import odom_from_state


def test_odom_from_state():
    s = ul.HighState()
    s.position = (1.0, -2.0, 0.5)
    s.quaternion = (math.cos(0.3), 0.0, 0.0, math.sin(0.3))  # w, x, y, z: yaw 0.6 rad
    s.velocity = (0.2, -0.1, 0.0)
    s.gyroscope = (0.01, 0.02, 0.4)
    s.body_height = 0.2
    v = odom_from_state(ul.HighState.unpack(s.pack()))
    assert v.position == pytest.approx((1.0, -2.0, 0.0))  # planar odom frame
    x, y, z, w = v.orientation
    assert 2 * math.atan2(z, w) == pytest.approx(0.6, abs=1e-6) and x == 0.0 and y == 0.0
    assert v.linear == pytest.approx((0.2, -0.1, 0.0)) and v.angular == pytest.approx((0.01, 0.02, 0.4))
    assert v.body_height == pytest.approx(0.2)
