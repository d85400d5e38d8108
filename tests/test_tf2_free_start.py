"""Issue 28: the safety-path nodes start where ``tf2_py`` does not import (Melodic, Python 3).

On Melodic the compiled ``tf2_py`` is built for Python 2.7, so ``import tf2_ros`` fails under
Python 3. A ``sitecustomize`` on PYTHONPATH makes ``import tf2_py`` fail the same way; each
Python node of the robot's safety path (driver, controller, position controller, navigation,
gesture receiver, bridge, and ``static_tf`` for the mounts) is started with it and must register
with the master and stay up. (The zone, rbd_lidar, is C++: tf2_py is not involved.) Nodes that
need tf2_py instead stop with a FATAL naming the fix: rbd_preflight's preflight does.
"""

import os
import socket
import sys
import time

import pytest
import rosgraph

from rbd_testkit import free_port, wait_for

SHIM = '''"""Test shim: tf2_py does not import, as on Melodic with Python 3."""
import sys


class _BlockTf2Py:
    def find_spec(self, name, path=None, target=None):
        if name == "tf2_py" or name.startswith("tf2_py."):
            raise ImportError("tf2_py blocked by the test (as on Melodic under Python 3)")
        return None


sys.meta_path.insert(0, _BlockTf2Py())
'''


@pytest.fixture()
def blocked_env(ros_env, tmp_path):
    """ros_env's environment with the tf2_py block on PYTHONPATH."""
    (tmp_path / "sitecustomize.py").write_text(SHIM)
    env = dict(ros_env.env)
    env["PYTHONPATH"] = str(tmp_path) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _lcm_url() -> str:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return "udpm://239.255.76.67:%d?ttl=0" % s.getsockname()[1]


def _run(ros_env, cmd, env, timeout=60.0):
    """(exit code, output) of cmd run to its end with env."""
    proc = ros_env.start(cmd, env=env)
    proc.wait(timeout=timeout)
    return proc.returncode, ros_env.output(proc)


def test_the_shim_blocks_tf2_ros(ros_env, blocked_env):
    code, out = _run(ros_env, [sys.executable, "-c", "import tf2_ros"], ros_env.env)
    assert code == 0, out  # importable here: the block below is the shim's doing
    code, out = _run(ros_env, [sys.executable, "-c", "import tf2_ros"], blocked_env)
    assert code != 0 and "tf2_py blocked by the test" in out, out


NODES = {  # node name -> command (navigation and the gesture receiver need their launch files' config)
    "tf2free_rbd_a1_driver": ["rosrun", "rbd_a1_driver", "rbd_a1_driver", "_lcm_url:=" + _lcm_url()],
    "tf2free_rbd_controller": ["rosrun", "rbd_controller", "rbd_controller"],
    "tf2free_rbd_pos_controller": ["rosrun", "rbd_pos_controller", "rbd_pos_controller"],
    "rbd_navigation": ["roslaunch", "rbd_navigation", "rbd_navigation.launch"],
    "rbd_gestrec": ["roslaunch", "rbd_gestrec", "rbd_gestrec.launch"],
    "tf2free_rbd_bridge": ["rosrun", "rbd_bridge", "rbd_bridge", "_address:=127.0.0.1", "_port:=%d" % free_port()],
    "tf2free_static_tf": ["rosrun", "rbd_description", "static_tf", "0.1", "0", "0.2", "0", "0", "0",
                          "base_link", "os1"],
}


def test_safety_path_nodes_start_without_tf2_py(ros_env, blocked_env):
    procs = {}
    for name, cmd in NODES.items():
        if cmd[0] == "rosrun":
            cmd = cmd[:3] + ["__name:=" + name] + cmd[3:]
        procs[name] = ros_env.start(cmd, name=name, env=blocked_env)
    master = rosgraph.Master("/tf2free_test", master_uri=ros_env.uri)
    waiting = set(procs)

    def registered():
        for name in sorted(waiting):
            assert procs[name].poll() is None, "%s exited:\n%s" % (name, ros_env.output(procs[name])[-3000:])
            try:
                master.lookupNode("/" + name)
                waiting.discard(name)
            except rosgraph.MasterError:
                pass
        return not waiting

    wait_for(registered, 60.0, 0.2)
    assert not waiting, "not registered in 60 s: %s\n%s" % (sorted(waiting), ros_env.tails())
    time.sleep(3.0)  # and they stay up
    for name, proc in procs.items():
        out = ros_env.output(proc)
        assert proc.poll() is None, "%s exited:\n%s" % (name, out[-3000:])
        assert "tf2_py" not in out, out[-3000:]


def test_preflight_stops_with_a_fatal_that_names_the_fix(ros_env, blocked_env):
    code, out = _run(ros_env, ["rosrun", "rbd_preflight", "preflight", "--duration", "1"], blocked_env)
    assert code != 0, out
    assert "tf2_ros does not import" in out and "geometry2 from source" in out, out
