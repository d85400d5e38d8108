"""A private ROS master on a free port plus roslaunch pieces, stopped by PID when done."""

import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time


def free_port():
    """A TCP port on 127.0.0.1 that is free right now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Stack:
    """rosmaster on a free port with its own ROS_HOME; this process's environment points at it."""

    def __init__(self, log_dir):
        self.home = tempfile.mkdtemp(prefix="rbd-exp-home.")
        self.port = free_port()
        self.log_dir = log_dir
        os.makedirs(log_dir, exist_ok=True)
        os.environ.update(ROS_MASTER_URI="http://127.0.0.1:%d" % self.port, ROS_HOME=self.home,
                          ROS_LOG_DIR=os.path.join(self.home, "log"), ROS_IP="127.0.0.1")
        os.environ.pop("ROS_HOSTNAME", None)
        self.env = dict(os.environ)
        self.procs = []
        self.start("rosmaster", ["rosmaster", "--core", "-p", str(self.port)])
        deadline = time.monotonic() + 30
        while True:
            try:
                socket.create_connection(("127.0.0.1", self.port), 0.5).close()
                break
            except OSError as exc:
                if time.monotonic() > deadline:
                    raise RuntimeError("rosmaster did not start") from exc
                time.sleep(0.1)

    def start(self, name, cmd):
        """Start cmd in its own process group, output to LOG_DIR/name.log."""
        log = open(os.path.join(self.log_dir, name + ".log"), "w")
        proc = subprocess.Popen(cmd, env=self.env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        self.procs.append(proc)
        return proc

    def launch(self, name, *args):
        """roslaunch against this master (package + file + args, or a file path)."""
        return self.start(name, ["roslaunch"] + list(args))

    def close(self):
        """SIGINT every process group (newest first), SIGKILL what does not stop; remove ROS_HOME."""
        for proc in reversed(self.procs):
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGINT)
        for proc in reversed(self.procs):
            try:
                proc.wait(25)  # roslaunch itself escalates SIGINT -> SIGTERM after 15 s
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
        # roslaunch starts every node in its own session: SIGKILL any node left with our ROS_HOME.
        for pid in self._leftovers():
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        shutil.rmtree(self.home, ignore_errors=True)

    def _leftovers(self):
        """PIDs of processes whose environment has this stack's (unique) ROS_HOME."""
        mark = ("ROS_HOME=%s" % self.home).encode()
        out = []
        for entry in os.listdir("/proc"):
            if not entry.isdigit() or int(entry) == os.getpid():
                continue
            try:
                with open("/proc/%s/environ" % entry, "rb") as fh:
                    if mark in fh.read().split(b"\0"):
                        out.append(int(entry))
            except OSError:
                continue
        return out
