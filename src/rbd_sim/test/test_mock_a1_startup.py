"""Bad parameters of mock_a1: a clear error at startup and a non-zero exit."""

import pytest


@pytest.mark.parametrize(
    "arg, message",
    [("_latency:=2.0", "latency must be in"), ("_drift_per_180:=nan", "drift_per_180 must be a finite number")],
)
def test_mock_a1_rejects_bad_parameters(ros_env, arg, message):
    rc, log = ros_env.run_to_exit(["rosrun", "rbd_sim", "mock_a1", arg])
    assert rc != 0
    assert message in log, log
