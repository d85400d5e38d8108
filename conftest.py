"""Shared pytest fixtures: free ports, a private ROS master, launched processes.

Every process a fixture starts is stopped by PID when the test ends; nothing assumes
11311 or 9090 are free.
"""

import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time

import pytest

# Started in the background by a non-interactive shell (nohup, `cmd &` in a script, some CI
# runners), this process inherits SIGINT as *ignored*, and so would every child: rosmaster and
# roslaunch would then ignore the SIGINT that stops them, and each stop would wait for the
# SIGKILL fallback (10 s per test here). A handler in this process makes children start with
# the default disposition again.
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


def free_port():
    """Return a TCP port on 127.0.0.1 that is free right now."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for_port(port, timeout=20.0):
    """Block until something accepts TCP connections on 127.0.0.1:port."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=0.5):
                return
        except OSError:
            time.sleep(0.05)
    raise TimeoutError("nothing listens on port %d after %.0f s" % (port, timeout))


def stop_process(proc, timeout=10.0):
    """SIGINT the process group of proc (as roslaunch expects), then SIGKILL if needed."""
    if proc.poll() is not None:
        return
    try:
        os.killpg(proc.pid, signal.SIGINT)
        proc.wait(timeout=timeout)
    except (subprocess.TimeoutExpired, ProcessLookupError):
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait()


class RosEnv:
    """A private ROS master on a free port with its own ROS_HOME, plus process helpers."""

    def __init__(self):
        self.home = tempfile.mkdtemp(prefix="rbd-ros-home.")
        self.port = free_port()
        self.env = dict(os.environ)
        self.env.update(
            ROS_MASTER_URI="http://127.0.0.1:%d" % self.port,
            ROS_HOME=self.home,
            ROS_LOG_DIR=os.path.join(self.home, "log"),
            ROS_IP="127.0.0.1",
        )
        self.env.pop("ROS_HOSTNAME", None)
        self.procs = []
        self.master = self.start(["rosmaster", "--core", "-p", str(self.port)])
        wait_for_port(self.port)

    def start(self, cmd, **kwargs):
        """Start cmd in its own process group with this master's environment."""
        log = open(os.path.join(self.home, "proc-%d.log" % len(self.procs)), "w")
        proc = subprocess.Popen(
            cmd, env=self.env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True, **kwargs
        )
        self.procs.append(proc)
        return proc

    def run_to_exit(self, cmd, timeout=60.0):
        """Run cmd (e.g. a node with bad parameters) until it exits; return (exit code, its output)."""
        proc = self.start(cmd)
        proc.wait(timeout=timeout)
        with open(os.path.join(self.home, "proc-%d.log" % self.procs.index(proc))) as f:
            return proc.returncode, f.read()

    def use_in_this_process(self):
        """Point this process's rospy/rosgraph at the private master."""
        for key in ("ROS_MASTER_URI", "ROS_HOME", "ROS_LOG_DIR", "ROS_IP"):
            os.environ[key] = self.env[key]

    def close(self):
        """Stop every started process (newest first) and remove ROS_HOME."""
        for proc in reversed(self.procs):
            stop_process(proc)
        shutil.rmtree(self.home, ignore_errors=True)


@pytest.fixture
def ros_env():
    """A private ROS master for one test."""
    env = RosEnv()
    try:
        yield env
    finally:
        env.close()
