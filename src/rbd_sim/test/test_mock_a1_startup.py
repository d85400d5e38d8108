"""Bad parameters of mock_a1: a clear error at startup and a non-zero exit."""

import os

import pytest


def run_node(ros_env, pkg, node, *args):
    proc = ros_env.start(["rosrun", pkg, node] + list(args))
    proc.wait(timeout=60)
    with open(os.path.join(ros_env.home, "proc-%d.log" % (len(ros_env.procs) - 1))) as f:
        return proc.returncode, f.read()


@pytest.mark.parametrize(
    "arg, message",
    [("_latency:=2.0", "latency must be in"), ("_drift_per_180:=nan", "drift_per_180 must be a finite number")],
)
def test_mock_a1_rejects_bad_parameters(ros_env, arg, message):
    rc, log = run_node(ros_env, "rbd_sim", "mock_a1", arg)
    assert rc != 0
    assert message in log, log
