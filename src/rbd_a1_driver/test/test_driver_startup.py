"""Bad parameters of rbd_a1_driver: a clear error at startup and a non-zero exit."""

import os

import pytest


def run_node(ros_env, pkg, node, *args):
    proc = ros_env.start(["rosrun", pkg, node] + list(args))
    proc.wait(timeout=60)
    with open(os.path.join(ros_env.home, "proc-%d.log" % (len(ros_env.procs) - 1))) as f:
        return proc.returncode, f.read()


@pytest.mark.parametrize(
    "arg, message",
    [("_send_rate:=5", "send_rate must be in"), ("_max_wz:=inf", "max_wz must be a finite number")],
)
def test_driver_rejects_bad_parameters(ros_env, arg, message):
    rc, log = run_node(ros_env, "rbd_a1_driver", "rbd_a1_driver", arg)
    assert rc != 0
    assert message in log, log
