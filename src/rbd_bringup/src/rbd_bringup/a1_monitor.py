"""What the (mock) A1 is told to do: the Unitree HighCmd stream on LCM, as seen by the robot.

Safety tests and the demo measure "zero velocity at the A1" on the commands the A1 actually
receives (``LCM_High_Cmd`` on the mock A1's LCM URL), not on what a node believes it sent. The
packets are decoded with the robot side's description of the wire (``rbd_sim.unitree_wire``, the
mock A1's), not with the driver's own layout module. This module is ROS-free; the clock and the
sink for the samples are the caller's.

Also holds a small helper the rbd_bringup rostests share (``report_fault_result``); waiting comes
from the test kit (``rbd_testkit.wait_for``), a yaw from ``rbd_geometry.rotation``.
"""

import json
import math
import os
import threading
import time
from typing import Callable, Dict, List, Optional, Tuple

from rbd_sim import unitree_wire as wire

Sample = Tuple[float, float]  # (time, commanded speed)


def command_speed(cmd: wire.Command) -> float:
    """Commanded speed of a HighCmd: max(|v_xy| [m/s], |yaw speed| [rad/s]); 0 unless walking.

    Args:
        cmd: a decoded HighCmd.

    Returns:
        The speed; 0.0 for any mode other than velocity walking (force stand does not move).
    """
    if cmd.mode != wire.MODE_VELOCITY_WALK:
        return 0.0
    return max(math.hypot(cmd.velocity[0], cmd.velocity[1]), abs(cmd.yawSpeed))


def command_velocity(cmd: wire.Command) -> Tuple[float, float, float]:
    """Commanded body velocity of a HighCmd: (forward [m/s], left [m/s], yaw [rad/s]); zeros unless walking."""
    if cmd.mode != wire.MODE_VELOCITY_WALK:
        return (0.0, 0.0, 0.0)
    return (float(cmd.velocity[0]), float(cmd.velocity[1]), float(cmd.yawSpeed))


class HighCmdMonitor:
    """Records every HighCmd the A1 receives on an LCM URL, in a background thread.

    Each valid packet becomes one sample ``(clock(), command_speed(cmd))`` passed to ``record``
    (default: appended to :attr:`samples`). Packets that do not decode are counted in
    :attr:`bad` and otherwise ignored.

    Args:
        url: LCM URL, e.g. ``udpm://239.255.76.67:7667?ttl=0`` (the mock A1's ``/rbd_sim/lcm_url``).
        record: called with (time, speed) for every valid command; runs in the LCM thread.
        record_velocity: if given, also called with (time, (vx, vy, wz)) for every valid command
            (the direction of the motion, see :func:`command_velocity`); runs in the LCM thread.
        clock: time source for the samples (``time.monotonic`` or ``time.time``).
        channel: LCM channel of the commands.
    """

    def __init__(
        self,
        url: str,
        record: Optional[Callable[[float, float], None]] = None,
        clock: Callable[[], float] = time.monotonic,
        channel: str = wire.CHANNEL_HIGH_CMD,
        record_velocity: Optional[Callable[[float, Tuple[float, float, float]], None]] = None,
    ) -> None:
        import lcm  # here, so that importing the module needs no LCM

        self.url = url
        self.clock = clock
        self.lock = threading.Lock()
        self.samples = []  # type: List[Sample]
        self.bad = 0
        self._record = record if record is not None else self._append
        self._record_velocity = record_velocity
        self._lc = lcm.LCM(url)
        self._lc.subscribe(channel, self._on_packet)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="a1_monitor", daemon=True)
        self._thread.start()

    def _append(self, t: float, speed: float) -> None:
        with self.lock:
            self.samples.append((t, speed))

    def _on_packet(self, _channel: str, data: bytes) -> None:
        try:
            cmd = wire.decode_high_cmd(data)
        except wire.WireError:
            self.bad += 1
            return
        now = self.clock()
        self._record(now, command_speed(cmd))
        if self._record_velocity is not None:
            self._record_velocity(now, command_velocity(cmd))

    def _loop(self) -> None:
        while not self._stop.is_set():
            self._lc.handle_timeout(100)

    def snapshot(self) -> List[Sample]:
        """A copy of the samples recorded so far (default sink only)."""
        with self.lock:
            return list(self.samples)

    def close(self) -> None:
        """Stop the receive thread (within ~0.1 s)."""
        self._stop.set()
        self._thread.join(2.0)


def stop_delay(samples: List[Sample], t0: float, t1: float, still: float) -> Optional[float]:
    """Delay after t0 from which every sample up to t1 is below ``still``.

    Args:
        samples: (time, value) pairs in time order.
        t0: start of the window (the fault / the stop request).
        t1: end of the window.
        still: values below this count as stopped.

    Returns:
        Seconds from t0 to the first sample of the final all-still run (0.0 if already still at
        t0); None if there are no samples in the window or the last one is not still.
    """
    window = [(t, v) for t, v in samples if t0 <= t <= t1]
    if not window:
        return None
    stop = t0  # type: Optional[float]
    for t, v in window:
        if v >= still:
            stop = None
        elif stop is None:
            stop = t
    if stop is None:
        return None
    return max(0.0, stop - t0)


def report_fault_result(result: Dict[str, object]) -> str:
    """Print one ``FAULT_RESULT {json}`` line and append it to ``$RBD_FAULT_LOG`` if that is set.

    Args:
        result: the measurement of one fault injection (JSON-serialisable values).

    Returns:
        The JSON text of the line, for the caller's own log.
    """
    line = json.dumps(result, sort_keys=True)
    print("FAULT_RESULT " + line, flush=True)
    path = os.environ.get("RBD_FAULT_LOG")
    if path:
        with open(path, "a") as fh:
            fh.write(line + "\n")
    return line
