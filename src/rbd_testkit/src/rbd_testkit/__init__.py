"""RoboDog's one test kit (issue #19): one definition of each helper the tests and tools share.

ROS-free at import (rospy is imported only by ``rbd_testkit.ros``); runs on Python 3.6+.

- ``free_port()``, ``wait_for_port(port, timeout, proc=...)``: ports on 127.0.0.1.
- ``wait_for(predicate, timeout, what=...)``: poll a condition instead of sleeping.
- ``wait_quiet(read, quiet, timeout)``: until a value kept still for ``quiet`` seconds (drained, settled).
- ``stays_unchanged(read, arrived, hold, send=...)``: "nothing happened", after proving the input arrived.
- ``RosEnv``: a private ROS master with its own ROS_HOME; start, launch, run to exit, stop by PID.
- ``stop_process(proc)`` / ``stop_processes(procs)``: process group SIGINT -> SIGKILL.
- ``restore_sigint()``: the SIGINT guard for processes started with SIGINT ignored.
- ``rbd_testkit.pytest_plugin``: the ``ros_env`` fixture (loaded by the conftests).
- ``rbd_testkit.ros``: ``run_rostest`` (shuffled method order), ``RosoutWatcher``, ``subscriber_nodes``,
  ``messages_received``.
"""

from rbd_testkit.ports import free_port, wait_for_port
from rbd_testkit.process import restore_sigint, stop_process, stop_processes
from rbd_testkit.ros_env import RosEnv
from rbd_testkit.wait import WaitTimeoutError, stays_unchanged, wait_for, wait_quiet

__all__ = [
    "RosEnv",
    "WaitTimeoutError",
    "free_port",
    "restore_sigint",
    "stays_unchanged",
    "stop_process",
    "stop_processes",
    "wait_for",
    "wait_for_port",
    "wait_quiet",
]
