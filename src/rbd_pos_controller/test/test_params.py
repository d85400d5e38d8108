"""Params refuses tolerances and options that would make the controller misbehave."""

import pytest

from rbd_pos_controller.params import Params


def test_invalid_params_rejected():
    with pytest.raises(ValueError):
        Params(position_tolerance=0.0)
    with pytest.raises(ValueError):
        Params(pose_timeout=float("nan"))
    with pytest.raises(ValueError):
        Params(body_pose_settle=-1.0)
