"""Processes started by tests: the SIGINT guard, stopping a process group, leftovers by environment."""

import os
import signal
import subprocess
import time
from typing import List, Sequence, Set


def restore_sigint() -> bool:
    """Give SIGINT its default handler back when this process was started with it ignored.

    A process started in the background by a non-interactive shell (``nohup``, ``cmd &`` in a
    script, some CI runners) inherits SIGINT as *ignored*, and so does every child it starts:
    rosmaster and roslaunch would then ignore the SIGINT that stops them, and every stop would
    wait for the SIGKILL fallback. With a handler installed here, children start with the
    default disposition again. Call it once, early (the pytest plugin and the tools do).

    Returns:
        True when SIGINT was ignored and is now handled (KeyboardInterrupt).
    """
    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        return True
    return False


def _signal_group(proc: subprocess.Popen, sig: int) -> bool:
    """Send ``sig`` to the process group led by ``proc``; False when the group is gone."""
    try:
        os.killpg(proc.pid, sig)
        return True
    except ProcessLookupError:
        return False


def stop_processes(procs: Sequence[subprocess.Popen], timeout: float = 10.0, term_timeout: float = 0.0) -> None:
    """Stop processes and their process groups together: SIGINT, then (optionally) SIGTERM, then SIGKILL.

    Every process must lead its own process group (``start_new_session=True``), as every
    process the kit starts does. All groups get each signal at once, so stopping n processes
    takes one timeout, not n. SIGINT is what roslaunch and rosmaster expect; roslaunch itself
    escalates to SIGTERM for nodes that ignore SIGINT after 15 s: give it ``timeout`` > 15 to let
    it. What is left of a group after its leader exited is killed too.

    Args:
        procs: the processes (group leaders).
        timeout: seconds to wait after SIGINT.
        term_timeout: seconds to wait after SIGTERM; 0 skips SIGTERM.
    """
    live = [p for p in procs if p.poll() is None]
    signalled = list(live)
    stages = [(signal.SIGINT, timeout)]
    if term_timeout > 0:
        stages.append((signal.SIGTERM, term_timeout))
    for sig, wait in stages:
        if not live:
            break
        for proc in live:
            _signal_group(proc, sig)
        deadline = time.monotonic() + wait
        still = []
        for proc in live:
            try:
                proc.wait(timeout=max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                still.append(proc)
        live = still
    for proc in signalled:
        _signal_group(proc, signal.SIGKILL)  # the group's stragglers, or the leader itself
    for proc in live:
        proc.wait()
    if signalled:
        groups = {proc.pid for proc in signalled}
        deadline = time.monotonic() + 5.0
        while _group_members(groups) and time.monotonic() < deadline:  # SIGKILL is delivered asynchronously
            time.sleep(0.01)


def stop_process(proc: subprocess.Popen, timeout: float = 10.0, term_timeout: float = 0.0) -> int:
    """Stop one process and its process group (see ``stop_processes``).

    Args:
        proc: the process (group leader).
        timeout: seconds to wait after SIGINT.
        term_timeout: seconds to wait after SIGTERM; 0 skips SIGTERM.

    Returns:
        Its exit code (negative: the signal that ended it).

    Example:
        >>> stop_process(proc, timeout=25.0)  # doctest: +SKIP
    """
    stop_processes([proc], timeout, term_timeout)
    return proc.wait()


def pids_with_env(key: str, value: str) -> List[int]:
    """PIDs of the processes whose environment holds ``key=value`` (this process excluded).

    roslaunch starts every node in a session of its own, so a node left running by a stopped
    roslaunch is in no process group the caller knows; a unique ``ROS_HOME`` finds it.

    Args:
        key: environment variable name.
        value: its exact value.

    Returns:
        The PIDs (only processes this user may read).
    """
    mark = ("%s=%s" % (key, value)).encode()
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit() or int(entry) == os.getpid():
            continue
        try:
            with open("/proc/%s/environ" % entry, "rb") as fh:
                if mark in fh.read().split(b"\0"):
                    found.append(int(entry))
        except OSError:
            continue
    return found


def _group_members(groups: Set[int]) -> List[int]:
    """Running (not zombie) processes whose process group is one of ``groups``."""
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open("/proc/%s/stat" % entry) as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue
        if fields[0] != "Z" and int(fields[2]) in groups:
            found.append(int(entry))
    return found


def _running(pid: int) -> bool:
    """True while ``pid`` exists and is not a zombie."""
    try:
        with open("/proc/%d/stat" % pid) as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return False


def kill_pids(pids: List[int], timeout: float = 5.0) -> List[int]:
    """SIGKILL each PID that still exists and wait until they are gone.

    Args:
        pids: process ids.
        timeout: seconds to wait for them to end.

    Returns:
        The PIDs still running after ``timeout`` (normally none).
    """
    for pid in pids:
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass
    deadline = time.monotonic() + timeout
    left = [pid for pid in pids if _running(pid)]
    while left and time.monotonic() < deadline:
        time.sleep(0.01)
        left = [pid for pid in left if _running(pid)]
    return left
