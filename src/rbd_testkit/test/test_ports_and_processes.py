"""free_port, wait_for_port, the SIGINT guard and process-group stops, on real sockets and processes."""

import os
import signal
import socket
import subprocess
import sys
import textwrap
import threading
import time

import pytest

from rbd_testkit import free_port, restore_sigint, stop_process, stop_processes, wait_for_port
from rbd_testkit.process import pids_with_env

# A child that ignores SIGINT and SIGTERM and prints its own child's pid: the stop must reach both.
STUBBORN = textwrap.dedent("""
    import signal, subprocess, sys, time
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    print(child.pid, flush=True)
    time.sleep(60)
""")


def start(code, **kwargs):
    return subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, universal_newlines=True,
                            start_new_session=True, **kwargs)


def alive(pid):
    try:
        with open("/proc/%d/stat" % pid) as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def test_free_port_can_be_bound():
    port = free_port()
    with socket.socket() as s:
        s.bind(("127.0.0.1", port))


def test_free_port_is_below_the_kernels_ephemeral_range():
    """Every bind to port 0 (ROS nodes' servers) and outgoing connection takes an ephemeral port at
    any time: one found free there may be gone before the caller's server binds it."""
    with open("/proc/sys/net/ipv4/ip_local_port_range") as fh:
        low, high = (int(v) for v in fh.read().split())
    ports = [free_port() for _ in range(20)]
    assert [p for p in ports if low <= p <= high] == []
    assert len(set(ports)) == len(ports), "a port handed out twice"


def test_free_port_does_not_follow_the_seeded_random_module():
    """pytest-randomly seeds ``random`` alike in both test lanes: the lanes' ports must not follow it."""
    code = "import random; random.seed(7); from rbd_testkit import free_port; print([free_port() for _ in range(3)])"
    runs = [subprocess.run([sys.executable, "-c", code], stdout=subprocess.PIPE, universal_newlines=True,
                           check=True).stdout for _ in range(2)]
    assert runs[0] != runs[1], runs


def test_wait_for_port_returns_once_something_listens():
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        port = server.getsockname()[1]
        threading.Timer(0.2, server.listen).start()
        wait_for_port(port, timeout=10.0)


def test_wait_for_port_times_out_and_notices_a_dead_process():
    port = free_port()
    with pytest.raises(TimeoutError, match=str(port)):
        wait_for_port(port, timeout=0.2)
    proc = subprocess.Popen([sys.executable, "-c", "raise SystemExit(3)"])
    proc.wait()
    with pytest.raises(RuntimeError, match="exited with 3"):
        wait_for_port(port, timeout=30.0, proc=proc)


def test_restore_sigint_gives_back_the_default_handler():
    code = "import signal; from rbd_testkit import restore_sigint; print(restore_sigint(), " \
           "signal.getsignal(signal.SIGINT) is signal.default_int_handler)"
    ignored = subprocess.run([sys.executable, "-c", code], stdout=subprocess.PIPE, universal_newlines=True,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN), check=True)
    assert ignored.stdout.split() == ["True", "True"]
    assert restore_sigint() is False  # pytest runs with a handler already: nothing to do


def test_stop_process_sigint_is_enough_for_a_well_behaved_process():
    proc = start("import time; print('up', flush=True); time.sleep(60)")
    assert proc.stdout.readline().strip() == "up"
    code = stop_process(proc, timeout=10.0)
    assert code == -signal.SIGINT  # stopped by SIGINT (KeyboardInterrupt), not killed
    proc.stdout.close()


def test_stop_processes_kills_stubborn_groups_with_their_children_in_one_timeout():
    procs = [start(STUBBORN), start(STUBBORN)]
    children = [int(p.stdout.readline()) for p in procs]
    t0 = time.monotonic()
    stop_processes(procs, timeout=1.0, term_timeout=0.5)
    took = time.monotonic() - t0
    assert [p.returncode for p in procs] == [-signal.SIGKILL] * 2
    assert not [pid for pid in children if alive(pid)]
    assert took < 2 * (1.0 + 0.5)  # both groups were signalled together, not one after the other
    for p in procs:
        p.stdout.close()


def test_pids_with_env_finds_a_process_by_a_unique_variable():
    mark = "rbd-testkit-%d" % os.getpid()
    proc = start("import time; print('up', flush=True); time.sleep(60)", env=dict(os.environ, RBD_MARK=mark))
    try:
        assert proc.stdout.readline().strip() == "up"
        assert pids_with_env("RBD_MARK", mark) == [proc.pid]
    finally:
        stop_process(proc)
        proc.stdout.close()
    assert pids_with_env("RBD_MARK", mark) == []
