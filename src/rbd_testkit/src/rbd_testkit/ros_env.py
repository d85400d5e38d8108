"""A private ROS master on a free port with its own ROS_HOME, and the processes started against it."""

import os
import shutil
import subprocess
import tempfile
import uuid
from typing import Any, Dict, List, Optional, Sequence, Tuple
from xmlrpc.client import ServerProxy

from rbd_testkit.ports import LOCALHOST, free_port, wait_for_port
from rbd_testkit.process import kill_pids, pids_with_env, stop_processes

ROS_KEYS = ("ROS_MASTER_URI", "ROS_HOME", "ROS_LOG_DIR", "ROS_IP")


class RosEnv:
    """rosmaster on a free 127.0.0.1 port with a fresh ROS_HOME; processes started against it.

    The one harness of the repository: the ``ros_env`` pytest fixture, the rbd_bridge test
    fixtures, the experiments, the soak and the demo use it. Every process it starts leads its
    own process group; ``close()`` stops them (SIGINT, then SIGKILL), kills any node that
    roslaunch left behind (found by this environment's unique ROS_HOME) and removes ROS_HOME.

    Attributes:
        home: the private ROS_HOME (removed by ``close()``).
        port: the master's TCP port.
        uri: the master's URI.
        env: the environment for processes (os.environ with the ROS_* variables above).
        master: the rosmaster process.
        log_dir: where each started process's output goes (``<name>.log``).
        procs: every process started, oldest first (the master first).

    Example:
        >>> with RosEnv() as env:  # doctest: +SKIP
        ...     env.launch("rbd_sim", "mock_a1.launch", "seed:=3", name="mock_a1")
        ...     code, out = env.run_to_exit(["rosrun", "rbd_sim", "mock_a1", "_bad:=1"])
    """

    def __init__(
        self,
        log_dir: Optional[str] = None,
        use_here: bool = False,
        master_timeout: float = 30.0,
        prefix: str = "rbd-ros-home.",
    ) -> None:
        """Start the master and wait until it accepts connections.

        Args:
            log_dir: directory for the processes' output; None: inside ROS_HOME (removed on close).
            use_here: also point this process (rospy, rosgraph, children started without this
                object) at the master, as ``use_in_this_process()`` does.
            master_timeout: seconds the master may take to listen.
            prefix: name prefix of the ROS_HOME directory.

        Raises:
            TimeoutError: the master does not listen in time (it is stopped again).
            RuntimeError: the master exited at once.
        """
        self.home = tempfile.mkdtemp(prefix=prefix)
        self.log_dir = log_dir or os.path.join(self.home, "output")
        os.makedirs(self.log_dir, exist_ok=True)
        self.port = free_port()
        self.uri = "http://%s:%d" % (LOCALHOST, self.port)
        self.env = dict(os.environ)
        self.env.update(ROS_MASTER_URI=self.uri, ROS_HOME=self.home, ROS_LOG_DIR=os.path.join(self.home, "log"),
                        ROS_IP=LOCALHOST)
        # rospy writes INFO lines to stdout, block-buffered into a log file: without this a log read
        # while the node runs lacks them (a clean environment, e.g. a bare machine's `make test`).
        self.env["PYTHONUNBUFFERED"] = "1"
        self.env.pop("ROS_HOSTNAME", None)
        self.procs: List[subprocess.Popen] = []
        self._logs: Dict[int, Tuple[str, Any]] = {}
        if use_here:
            self.use_in_this_process()
        self.master = self.start(["rosmaster", "--core", "-p", str(self.port)], name="rosmaster")
        try:
            wait_for_port(self.port, timeout=master_timeout, proc=self.master)
            # As roscore does: one run_id before any roslaunch starts. Without it, two roslaunch
            # started together each declare their own and one dies ("run_id ... does not match").
            code, msg, _ = ServerProxy(self.uri).setParam("/rbd_testkit", "/run_id", str(uuid.uuid1()))
            if code != 1:
                raise RuntimeError("cannot set /run_id on the master: %s" % msg)
        except (TimeoutError, RuntimeError, OSError):
            self.close()
            raise

    def __enter__(self) -> "RosEnv":
        """Use as a context manager: ``close()`` on exit."""
        return self

    def __exit__(self, *exc: object) -> None:
        """Stop everything (see ``close``)."""
        self.close()

    def start(self, cmd: Sequence[str], name: Optional[str] = None, capture: bool = False,
              **popen_kwargs: Any) -> subprocess.Popen:
        """Start ``cmd`` in its own process group with this master's environment.

        Args:
            cmd: the command line.
            name: log file name (``<log_dir>/<name>.log``); default ``proc-<n>``.
            capture: give the caller the output as a text pipe (``proc.stdout``, undecodable bytes
                replaced) instead of a log file; the caller must keep reading it.
            **popen_kwargs: passed to ``subprocess.Popen`` (e.g. ``cwd``, ``env``).

        Returns:
            The process.
        """
        popen_kwargs.setdefault("env", self.env)
        path = os.path.join(self.log_dir, "%s.log" % (name or "proc-%d" % len(self.procs)))
        if capture:
            proc = subprocess.Popen(list(cmd), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                    universal_newlines=True, errors="replace", start_new_session=True,
                                    **popen_kwargs)
            self._logs[proc.pid] = (path, None)
        else:
            log = open(path, "w")
            try:
                proc = subprocess.Popen(list(cmd), stdout=log, stderr=subprocess.STDOUT, start_new_session=True,
                                        **popen_kwargs)
            except OSError:
                log.close()
                raise
            self._logs[proc.pid] = (path, log)
        self.procs.append(proc)
        return proc

    def launch(self, *args: str, **kwargs: Any) -> subprocess.Popen:
        """Start ``roslaunch`` against this master (``package file args...`` or a file path).

        Args:
            *args: roslaunch arguments.
            **kwargs: as for ``start`` (``name``, ``capture``, Popen arguments).

        Returns:
            The roslaunch process.
        """
        return self.start(["roslaunch"] + list(args), **kwargs)

    def output(self, proc: subprocess.Popen) -> str:
        """The output a process started with a log file has written so far.

        Args:
            proc: a process this object started (without ``capture``).

        Returns:
            Its log's text.
        """
        path, log = self._logs[proc.pid]
        if log is not None:
            log.flush()
        with open(path, encoding="utf-8", errors="replace") as f:
            return f.read()

    def tails(self, lines: int = 30) -> str:
        """The last lines of every log file, one block per process (for a failure report).

        Args:
            lines: lines per process.

        Returns:
            The text.
        """
        blocks = []
        for proc in self.procs:
            path, log = self._logs[proc.pid]
            if log is None:
                continue
            text = self.output(proc).splitlines()[-lines:]
            blocks.append("== %s (pid %d, exit %s)\n%s" % (os.path.basename(path), proc.pid, proc.poll(),
                                                             "\n".join(text)))
        return "\n".join(blocks)

    def run_to_exit(self, cmd: Sequence[str], timeout: float = 60.0) -> Tuple[int, str]:
        """Run ``cmd`` (e.g. a node with bad parameters) until it exits.

        Args:
            cmd: the command line.
            timeout: seconds it may run; then it is stopped and the test fails.

        Returns:
            (exit code, its output).

        Raises:
            AssertionError: it still ran after ``timeout`` seconds.
        """
        proc = self.start(cmd)
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            stop_processes([proc])
            raise AssertionError(
                "%s still ran after %.0f s:\n%s" % (" ".join(cmd), timeout, self.output(proc)[-3000:])) from None
        return proc.returncode, self.output(proc)

    def use_in_this_process(self) -> None:
        """Point this process (rospy, rosgraph, later children) at the private master."""
        for key in ROS_KEYS:
            os.environ[key] = self.env[key]
        os.environ.pop("ROS_HOSTNAME", None)

    def close(self, timeout: float = 10.0, term_timeout: float = 0.0) -> None:
        """Stop every started process, then the master; kill leftover nodes; remove ROS_HOME.

        Args:
            timeout: seconds each stage waits after SIGINT (> 15 lets roslaunch escalate itself).
            term_timeout: seconds to wait after SIGTERM; 0 goes from SIGINT straight to SIGKILL.
        """
        procs = getattr(self, "procs", [])
        master = getattr(self, "master", None)
        stop_processes([p for p in procs if p is not master], timeout, term_timeout)
        if master is not None:
            stop_processes([master], timeout, term_timeout)
        kill_pids(pids_with_env("ROS_HOME", self.home))  # nodes roslaunch started in sessions of their own
        for _path, log in getattr(self, "_logs", {}).values():
            if log is not None:
                log.close()
        for proc in procs:
            if proc.stdout is not None:
                proc.stdout.close()
        shutil.rmtree(self.home, ignore_errors=True)
        self.procs = []

