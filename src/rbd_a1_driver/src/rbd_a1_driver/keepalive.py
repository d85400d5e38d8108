"""Keep-alive of the HighCmd stream: a small process that fills the gaps when the driver's process stalls.

The SDK's ``lcm_server_high`` exits once it has gone 10 loops (20 ms) without a command on
``LCM_High_Cmd``. The driver sends every 4 ms from a Python thread, but on a loaded machine its
process can stall for 30-50 ms (a thread holding the GIL is preempted by another process; the
send thread waits for it). This process has a single thread and no ROS: the driver hands it a
copy of every HighCmd it publishes (through a pipe), and when none has come for ``gap`` seconds,
it publishes the driver's last command itself, every ``period``, until the driver sends again.

It never moves the robot more than the driver did: it repeats the driver's last command for at
most ``hold`` seconds after the driver's last packet, then the same command with zero velocity
and zero yaw rate. It also reads the HighStates: once one carries the remote's e-stop combination
(``REMOTE_MASK``, 0 = not watched), it fills with zero velocity only, until the driver itself has
sent a zero-velocity command after that HighState (the driver's own gate has then latched). So a
driver stalled right after the press does not have its last walk repeated. When the pipe closes
(the driver exits or dies), it stops at once.

Run by the driver as ``python -m rbd_a1_driver.keepalive URL PERIOD GAP HOLD REMOTE_MASK`` with the pipe on
stdin (records: the driver's send time and the HighCmd), in a session of its own (``setsid``):
with the kernel's autogroup scheduling, a session shares the CPU as one group, so the keep-alive
does not wait behind the driver's (or roslaunch's) busy threads; where it may (root or
CAP_SYS_NICE), it also takes the lowest real-time priority (SCHED_FIFO 1), so that its wake-ups
are not queued behind other processes on a loaded machine (it sleeps between packets and reads
the HighStates in batches: 2-3 % of a core at 250 Hz). It writes one line to stdout when it is
ready, naming its scheduling.
:class:`KeepAlive` is the ROS-free decision, tested on its own.
"""

import os
import select
import struct
import sys
import time
from typing import Callable, Optional

from rbd_a1_driver import unitree_layout as ul

#: One record on the pipe: the driver's send time (time.monotonic(), the same clock in every process
#: of the host) and the HighCmd bytes.
RECORD = struct.Struct("<d%ds" % ul.HIGH_CMD_SIZE)


def record(packet: bytes, sent: float) -> bytes:
    """The pipe record of a HighCmd the driver published at ``sent`` (monotonic)."""
    return RECORD.pack(sent, packet)


def publish_and_record(publish: Callable[[bytes], object], packet: bytes,
                       clock: Callable[[], float] = time.monotonic) -> bytes:
    """Publish ``packet`` and return its pipe record, stamped just *before* the publish.

    The keep-alive counts its gap from this stamp. Stamped after the publish, a stall of the
    driver's thread right after the packet left (a GIL wait on a loaded machine) would move the
    stamp by the stall, and the keep-alive, once it read that record, would wait stall + gap
    after the packet for its next fill. Early is harmless: after a stall between the stamp and
    the publish, the fill comes sooner and repeats the command just sent (``hold`` ends sooner).
    """
    sent = clock()
    publish(packet)
    return record(packet, sent)


def zero_velocity(packet: bytes) -> bytes:
    """The same HighCmd with velocity and yaw rate set to zero."""
    cmd = ul.HighCmd.unpack(packet)
    cmd.velocity = (0.0, 0.0)
    cmd.yaw_speed = 0.0
    return cmd.pack()


def at_rest(packet: bytes) -> bool:
    """True if the HighCmd commands zero velocity and zero yaw rate."""
    cmd = ul.HighCmd.unpack(packet)
    return tuple(cmd.velocity) == (0.0, 0.0) and cmd.yaw_speed == 0.0


class KeepAlive:
    """What to publish when the driver is silent.

    Args:
        period: send period while filling in [s].
        gap: silence of the driver after which filling starts [s] (below lcm_server_high's 20 ms).
        hold: how long after the driver's last packet its command is repeated as it was [s];
            after that with zero velocity.
        remote_mask: the remote's e-stop button bits (:func:`unitree_layout.button_mask`); 0 = the
            remote is not watched.

    Raises:
        ValueError: a non-positive period or gap, gap >= 0.02 s, or a negative hold.
    """

    def __init__(self, period: float, gap: float, hold: float, remote_mask: int = 0) -> None:
        if not (0.0 < period and 0.0 < gap < 0.02 and hold >= 0.0):
            raise ValueError("need period > 0, 0 < gap < 0.02 s and hold >= 0, got %r, %r, %r" % (period, gap, hold))
        self.period = period
        self.gap = gap
        self.hold = hold
        self.last = None  # type: Optional[bytes]
        self.last_time = 0.0
        self._zero = None  # type: Optional[bytes]
        self.next_fill = 0.0
        self.filled = 0
        self.remote_mask = int(remote_mask)
        self.remote_since = None  # type: Optional[float]  # e-stop press seen, driver not yet at rest

    def from_state(self, buttons: Optional[int], now: float) -> None:
        """A HighState with the remote's ``buttons`` (None: not a HighState) was read at ``now``."""
        if buttons is None or not self.remote_mask or buttons & self.remote_mask != self.remote_mask:
            return
        if self.remote_since is None:
            self.remote_since = now

    def from_driver(self, packet: bytes, now: float) -> None:
        """The driver published ``packet`` at ``now`` (its own send time, not when it was read here)."""
        if packet != self.last:
            self._zero = None
        if self.remote_since is not None and now >= self.remote_since and at_rest(packet):
            self.remote_since = None  # the driver has seen the press: its own gate holds the robot
        self.last = packet
        self.last_time = now
        self.next_fill = now + self.gap

    def due(self, now: float) -> Optional[bytes]:
        """The packet to publish at ``now``, or None while the driver itself is sending."""
        if self.last is None or now < self.next_fill:
            return None
        self.next_fill = max(self.next_fill + self.period, now)
        self.filled += 1
        if now - self.last_time <= self.hold and self.remote_since is None:
            return self.last
        if self._zero is None:
            self._zero = zero_velocity(self.last)
        return self._zero

    def wait(self, now: float) -> Optional[float]:
        """Seconds until the next fill could be due (None: nothing to fill yet)."""
        if self.last is None:
            return None
        return max(0.0, self.next_fill - now)


def realtime() -> str:
    """Take SCHED_FIFO priority 1 if allowed; returns the scheduling now in force, for the log."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(1))
        return "SCHED_FIFO 1"
    except (AttributeError, OSError) as e:  # not Linux, or no permission
        return "SCHED_OTHER (no real-time priority: %s)" % e


#: While the driver sends, the HighStates are read in batches this often [s] (a wake-up per packet
#: would cost a few % of a core); before every fill, all that have arrived are read.
STATE_BATCH_S = 0.02
#: LCM packets read at most in one batch (HighStates, and the HighCmds that share the group).
MAX_READS = 1000


def run(url: str, period: float, gap: float, hold: float, remote_mask: int = 0, fd: int = 0) -> int:
    """Read the driver's packets from ``fd`` and fill its silences on ``url`` until ``fd`` closes."""
    import lcm  # here, so that the module imports without LCM (unit tests)

    lc = lcm.LCM(url)
    keep = KeepAlive(period, gap, hold, remote_mask)
    if keep.remote_mask:
        lc.subscribe(ul.CHANNEL_HIGH_STATE, lambda _c, data: keep.from_state(ul.state_buttons(data), time.monotonic()))
    next_batch = 0.0
    size = RECORD.size
    pending = b""
    sys.stdout.write("ready %s\n" % realtime())
    sys.stdout.flush()
    while True:
        now = time.monotonic()
        timeout = keep.wait(now)
        if keep.remote_mask:
            timeout = max(0.0, min(next_batch - now, STATE_BATCH_S if timeout is None else timeout))
        ready, _, _ = select.select([fd], [], [], timeout)
        now = time.monotonic()
        if ready:
            data = os.read(fd, 65536)
            if not data:
                return 0  # the driver closed the pipe: it is gone
            pending += data
            whole = len(pending) - len(pending) % size
            if whole:
                sent, packet = RECORD.unpack(pending[whole - size:whole])
                keep.from_driver(packet, sent)
                pending = pending[whole:]
        if keep.remote_mask and (now >= next_batch or keep.wait(now) == 0.0):
            for _ in range(MAX_READS):  # every HighState that has arrived, before a fill is decided
                if lc.handle_timeout(0) <= 0:
                    break
            next_batch = now + STATE_BATCH_S
        packet = keep.due(now)
        if packet is not None:
            lc.publish(ul.CHANNEL_HIGH_CMD, packet)


def main() -> int:
    """Command line: URL PERIOD GAP HOLD [REMOTE_MASK] (the driver starts it)."""
    url, period, gap, hold = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])
    remote_mask = int(sys.argv[5]) if len(sys.argv) > 5 else 0
    try:
        return run(url, period, gap, hold, remote_mask)
    except KeyboardInterrupt:
        return 0


if __name__ == "__main__":
    sys.exit(main())
