"""The core (rbd_bridge.core) imports nothing of ROS: every module imported with rospy, genpy and roslib blocked."""

import subprocess
import sys

BLOCKED = ("rospy", "genpy", "roslib", "rosgraph", "rosservice", "std_msgs")

PROBE = r"""
import importlib, pkgutil, sys

BLOCKED = %r


class Blocker:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in BLOCKED:
            raise ImportError("blocked in this test: " + name)
        return None


sys.meta_path.insert(0, Blocker())
import rbd_bridge.core as core

names = [m.name for m in pkgutil.walk_packages(core.__path__, "rbd_bridge.core.")]
for name in names:
    importlib.import_module(name)
leaked = sorted(m for m in sys.modules if m.split(".")[0] in BLOCKED)
try:  # the blocker works: the ROS edge cannot be imported
    importlib.import_module("rbd_bridge.ros.topics")
    edge = "imported"
except ImportError as exc:
    edge = str(exc)
print(repr((names, leaked, edge)))
"""


def test_core_modules_import_with_ros_blocked():
    out = subprocess.run(  # noqa: UP022 (Python 3.6 has no capture_output)
        [sys.executable, "-c", PROBE % (BLOCKED,)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        universal_newlines=True,
        timeout=60,
    )
    assert out.returncode == 0, out.stderr
    names, leaked, edge = eval(out.stdout.strip().splitlines()[-1])
    expected = {"encoding", "fanout", "outqueue", "params", "rosapi", "security", "session", "tcpros", "types"}
    assert expected | {"websocket"} <= {n.rsplit(".", 1)[1] for n in names}
    assert leaked == []
    assert "blocked in this test" in edge
