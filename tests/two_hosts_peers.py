"""Helper processes of tests/test_two_hosts.py (issue 10, "Two hosts"); not a test module.

Run as ``python two_hosts_peers.py ROLE ...``. Every role prints one event per line on stdout,
``<kind> <time.monotonic()> <payload...>`` (the monotonic clock is shared by all network
namespaces, so the test compares times across processes), and reads commands from stdin; it
exits when stdin closes.

Roles:

- ``link NS_A IF_A NS_B IF_B SEED``: the WLAN between the two hosts. This kernel has no
  ``sch_netem`` (nor any tc classifier), so the link is emulated in user space: one TUN
  interface in each namespace, IP packets copied between them; ``set CUT LOSS DELAY`` drops
  everything (CUT=1), drops each packet with probability LOSS, delays each packet by DELAY
  seconds (each direction).
- ``probe``: in the robot namespace, the ground truth (``/rbd_sim/ground_truth`` speed),
  ``/rbd_controller/state`` and the heartbeats that reach the robot (``/rbd_local/heartbeat``).
- ``viewer``: in the laptop namespace, a ROS node on the robot's master (ROS multi-machine),
  subscribed like RViz to ``/rbd_controller/state`` and ``/ouster/points``.
- ``app HOST PORT``: in the laptop namespace, the laptop app's link
  (``rbd_local.link.RobotLink``: heartbeat, gestures, e-stop) over the bridge; commands
  ``gesture NAME`` and ``estop 0|1 TIMEOUT``.
"""

import ctypes
import fcntl
import heapq
import math
import os
import random
import select
import struct
import sys
import threading
import time

CLONE_NEWNET = 0x40000000
TUNSETIFF = 0x400454CA
IFF_TUN = 0x0001
IFF_NO_PI = 0x1000
_OUT_LOCK = threading.Lock()


def emit(kind: str, *payload: object) -> None:
    """Print one event line with the current monotonic time."""
    line = " ".join([kind, "%.4f" % time.monotonic()] + [str(p) for p in payload])
    with _OUT_LOCK:
        sys.stdout.write(line + "\n")
        sys.stdout.flush()


def open_tun(netns: str, ifname: str) -> int:
    """Create TUN interface ``ifname`` inside network namespace ``netns``; return its fd."""
    libc = ctypes.CDLL(None, use_errno=True)
    host = os.open("/proc/self/ns/net", os.O_RDONLY)
    target = os.open(os.path.join("/var/run/netns", netns), os.O_RDONLY)
    try:
        if libc.setns(target, CLONE_NEWNET) != 0:
            raise OSError(ctypes.get_errno(), "setns(%s) failed" % netns)
        try:
            fd = os.open("/dev/net/tun", os.O_RDWR | os.O_NONBLOCK)
            fcntl.ioctl(fd, TUNSETIFF, struct.pack("16sH", ifname.encode(), IFF_TUN | IFF_NO_PI))
        finally:
            if libc.setns(host, CLONE_NEWNET) != 0:
                raise OSError(ctypes.get_errno(), "setns back to the host namespace failed")
    finally:
        os.close(host)
        os.close(target)
    return fd


def run_link(ns_a: str, if_a: str, ns_b: str, if_b: str, seed: str) -> None:
    """Copy packets between the two TUN interfaces with the configured impairment."""
    fd_a = open_tun(ns_a, if_a)
    fd_b = open_tun(ns_b, if_b)
    peer = {fd_a: fd_b, fd_b: fd_a}
    rng = random.Random(int(seed))
    cut, loss, delay = False, 0.0, 0.0
    stats = {"forwarded": 0, "dropped": 0}
    pending = []  # heap of (due, seq, out_fd, packet)
    seq = 0
    emit("ready")
    while True:
        now = time.monotonic()
        timeout = max(0.0, pending[0][0] - now) if pending else 0.5
        readable, _, _ = select.select([fd_a, fd_b, 0], [], [], timeout)
        for fd in readable:
            if fd == 0:
                line = sys.stdin.readline()
                if not line:
                    return
                words = line.split()
                if words and words[0] == "set":
                    cut, loss, delay = words[1] == "1", float(words[2]), float(words[3])
                emit("ok", cut, loss, delay, stats["forwarded"], stats["dropped"])
                continue
            for _ in range(64):
                try:
                    packet = os.read(fd, 70000)
                except BlockingIOError:
                    break
                if cut or (loss > 0 and rng.random() < loss):
                    stats["dropped"] += 1
                    continue
                seq += 1
                heapq.heappush(pending, (time.monotonic() + delay, seq, peer[fd], packet))
        now = time.monotonic()
        while pending and pending[0][0] <= now:
            _due, _seq, out, packet = heapq.heappop(pending)
            try:
                os.write(out, packet)
                stats["forwarded"] += 1
            except OSError:
                stats["dropped"] += 1


def run_probe() -> None:
    """Robot side: ground-truth speed, controller state, heartbeats as they reach the robot."""
    import rospy
    from nav_msgs.msg import Odometry
    from rospy.msg import AnyMsg
    from std_msgs.msg import String

    from rbd_msgs.msg import ControllerState

    def stamp_mono(stamp: "rospy.Time") -> str:
        """A header stamp (wall clock) on the monotonic clock of the event lines."""
        return "%.4f" % (stamp.to_sec() - (time.time() - time.monotonic()))

    def on_truth(msg: Odometry) -> None:
        t = msg.twist.twist
        speed = max(math.hypot(t.linear.x, t.linear.y), abs(t.angular.z))
        emit("T", "%.4f" % speed, stamp_mono(msg.header.stamp))

    def on_controller_state(msg: ControllerState) -> None:
        emit("C", msg.state_name, stamp_mono(msg.header.stamp))

    rospy.init_node("two_hosts_probe", disable_signals=True)
    rospy.Subscriber("/rbd_sim/ground_truth", Odometry, on_truth, queue_size=50)
    rospy.Subscriber("/rbd_controller/state", String, lambda m: emit("S", m.data), queue_size=20)
    rospy.Subscriber("/rbd_controller/controller_state", ControllerState, on_controller_state, queue_size=20)
    rospy.Subscriber("/rbd_local/heartbeat", AnyMsg, lambda _m: emit("H"), queue_size=20)
    emit("ready")
    sys.stdin.read()  # until the test closes stdin
    rospy.signal_shutdown("stdin closed")


def run_viewer() -> None:
    """Laptop side: a ROS node on the robot's master, subscribed like RViz."""
    import rospy
    from sensor_msgs.msg import PointCloud2
    from std_msgs.msg import String

    rospy.init_node("laptop_viewer", disable_signals=True)
    rospy.Subscriber("/rbd_controller/state", String, lambda m: emit("S", m.data), queue_size=20)
    rospy.Subscriber("/ouster/points", PointCloud2, lambda _m: emit("P"), queue_size=1, buff_size=2**24)
    emit("ready")
    sys.stdin.read()
    rospy.signal_shutdown("stdin closed")


def run_app(host: str, port: str) -> None:
    """Laptop side: the rbd_local app's link over the bridge, driven by stdin commands."""
    from rbd_local.link import RobotLink

    link = RobotLink(
        host=host,
        port=int(port),
        on_state=lambda s: emit("S", s),
        on_connection=lambda up: emit("C", int(up)),
    )
    link.start()
    emit("ready")

    def estop(engage: bool, timeout: float) -> None:
        t0 = time.monotonic()
        ok, message = link.em_stop(engage, timeout=timeout)
        emit("E", int(engage), "%.4f" % t0, int(ok), message.replace("\n", " ") or "-")

    for line in sys.stdin:
        words = line.split()
        if not words:
            continue
        if words[0] == "gesture":
            emit("G", words[1], int(link.send_gesture(words[1])))
        elif words[0] == "estop":
            threading.Thread(target=estop, args=(words[1] == "1", float(words[2])), daemon=True).start()
    link.stop(timeout=3.0)


if __name__ == "__main__":
    role, args = sys.argv[1], sys.argv[2:]
    {"link": run_link, "probe": run_probe, "viewer": run_viewer, "app": run_app}[role](*args)
