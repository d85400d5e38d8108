"""RobotLink against the real rbd_bridge with a real ROS master (skipped when rbd_bridge is not built).

Run from a sourced catkin workspace (``source ./env.sh`` after ``make build``) that contains
rbd_bridge; the test starts its own roscore on a free port, ``roslaunch rbd_bridge
rbd_bridge.launch`` (the RoboDog allow-list) and a stand-in controller (ros_peer.py).
"""

import os
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time

import pytest

from rbd_local.link import RobotLink

HERE = os.path.dirname(os.path.abspath(__file__))


def _bridge_available():
    if not shutil.which("roscore") or not shutil.which("rospack"):
        return False
    proc = subprocess.run(["rospack", "find", "rbd_bridge"], capture_output=True, text=True, timeout=30)
    pkg = proc.stdout.strip()
    return proc.returncode == 0 and os.path.isfile(os.path.join(pkg, "launch", "rbd_bridge.launch"))


pytestmark = pytest.mark.skipif(
    not _bridge_available(), reason="rbd_bridge (with launch/rbd_bridge.launch) not in this sourced workspace"
)


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_port(port, timeout):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return True
        time.sleep(0.1)
    return False


class Lines:
    """Collect a process's stdout lines in a thread."""

    def __init__(self, proc):
        self.lines = []
        self._t = threading.Thread(target=self._read, args=(proc,), daemon=True)
        self._t.start()

    def _read(self, proc):
        for line in proc.stdout:
            self.lines.append(line.strip())

    def wait(self, pred, timeout=15):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if any(pred(x) for x in list(self.lines)):
                return True
            time.sleep(0.05)
        return False


@pytest.fixture
def ros_bridge():
    home = tempfile.mkdtemp(prefix="rbd-local-ros-")
    master_port, ws_port = _free_port(), _free_port()
    env = dict(os.environ, ROS_HOME=home, ROS_LOG_DIR=os.path.join(home, "log"), ROS_IP="127.0.0.1",
               ROS_MASTER_URI="http://127.0.0.1:%d" % master_port, PYTHONUNBUFFERED="1")
    env.pop("ROS_HOSTNAME", None)
    procs = []
    try:
        procs.append(subprocess.Popen(["roscore", "-p", str(master_port)], env=env, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL, start_new_session=True))
        assert _wait_port(master_port, 30), "roscore did not start"
        procs.append(subprocess.Popen(
            ["roslaunch", "rbd_bridge", "rbd_bridge.launch", "port:=%d" % ws_port, "address:=127.0.0.1"],
            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True))
        peer = subprocess.Popen([sys.executable, os.path.join(HERE, "ros_peer.py")], env=env, stdout=subprocess.PIPE,
                                stderr=subprocess.DEVNULL, text=True, start_new_session=True)
        procs.append(peer)
        lines = Lines(peer)
        assert lines.wait(lambda x: x == "READY", 30), "ROS peer did not start"
        assert _wait_port(ws_port, 30), "rbd_bridge did not open its port"
        yield ws_port, lines
    finally:
        for p in reversed(procs):
            if p.poll() is None:
                os.killpg(p.pid, 2)  # SIGINT: roslaunch/roscore shut down their children
        for p in reversed(procs):
            try:
                p.wait(15)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, 9)
                p.wait()
        shutil.rmtree(home, ignore_errors=True)


def test_link_through_the_real_bridge(ros_bridge):
    port, peer = ros_bridge
    got = {"status": [], "state": [], "moves": []}
    link = RobotLink("127.0.0.1", port, retry_s=0.3, on_status=got["status"].append, on_state=got["state"].append,
                     on_path_queue=got["moves"].append).start()
    try:
        assert link.wait_connected(20)
        # latched state arrives through the allow-listed subscriptions
        deadline = time.monotonic() + 15
        while time.monotonic() < deadline and not (got["status"] and got["state"] and got["moves"]):
            time.sleep(0.05)
        assert got["status"][:1] == ["idle"] and got["state"][:1] == ["WAITING_FOR_GESTURE"]
        assert got["moves"][:1] == [["walk: to (0.6, 0)", "walk: back"]]
        # a gesture published by the laptop arrives in ROS (retry: the bridge's advertise may lag)
        deadline = time.monotonic() + 15
        while time.monotonic() < deadline and "GESTURE walk" not in peer.lines:
            link.send_gesture("walk")
            peer.wait(lambda x: x == "GESTURE walk", 1.0)
        assert "GESTURE walk" in peer.lines
        assert peer.wait(lambda x: x.startswith("HEARTBEAT"), 10)
        # the e-stop reaches the controller and its answer comes back
        assert link.em_stop(True, timeout=10) == (True, "engaged")
        assert peer.wait(lambda x: x == "EMSTOP True", 5)
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and got["status"][-1:] != ["emergency"]:
            time.sleep(0.05)
        assert got["status"][-1] == "emergency"
    finally:
        link.stop()
