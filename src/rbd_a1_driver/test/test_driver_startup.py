"""Bad parameters of rbd_a1_driver: a clear error at startup and a non-zero exit."""

import pytest


@pytest.mark.parametrize(
    "arg, message",
    [("_send_rate:=5", "send_rate must be in"), ("_max_wz:=inf", "max_wz must be a finite number")],
)
def test_driver_rejects_bad_parameters(ros_env, arg, message):
    rc, log = ros_env.run_to_exit(["rosrun", "rbd_a1_driver", "rbd_a1_driver", arg])
    assert rc != 0
    assert message in log, log
