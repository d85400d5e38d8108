"""The robot's camera as a frame source: compressed images that arrive through the robot link.

:class:`~rbd_local.link.RobotLink` (``on_camera``) hands every sensor_msgs/CompressedImage
message of the robot's camera (the ZED2's left image on the A1) to :meth:`RobotCameraSource.push`
from its own thread. The gesture loop iterates over the source like over a webcam: it waits for
the next frame, always gets the *newest* one (frames that arrive while the loop is busy are
counted and dropped, never queued: a late frame would only delay the robot's reaction), and
each frame is timed by its camera stamp, so the classifier's window covers the real duration
of the gesture whatever the network does.

The source also measures itself (:meth:`RobotCameraSource.stats`): frames received, shown
and dropped, their rate, and two latencies from the camera's stamp: until the frame was
decoded on the laptop (transport) and until the gesture pipeline was done with it (call
:meth:`RobotCameraSource.frame_done`). The stamps come from the robot's clock, so the
latencies are exact only when both clocks agree (NTP/chrony on the robot and laptop, or one
machine).
"""

import base64
import binascii
import logging
import threading
import time

import numpy as np

LOG = logging.getLogger("rbd_local.gestures")


def decode_compressed(msg: dict) -> tuple[float, np.ndarray]:
    """Decode one sensor_msgs/CompressedImage message as the bridge sends it (JSON).

    Args:
        msg: {"header": {"stamp": {"secs", "nsecs"}, ...}, "format": "jpeg" | "png" |
            "bgr8; jpeg compressed bgr8" | ..., "data": base64 of the file}.

    Returns:
        (camera stamp [s] (0.0 when the message has none), BGR image).

    Raises:
        ValueError: for a message that is not a decodable JPEG or PNG image.
    """
    import cv2

    if not isinstance(msg, dict):
        raise ValueError("camera message is not a mapping")
    fmt = str(msg.get("format", "")).lower()
    if "jpeg" not in fmt and "jpg" not in fmt and "png" not in fmt:
        raise ValueError("camera image format %r is not jpeg or png" % fmt)
    try:
        raw = base64.b64decode(msg.get("data", ""), validate=True)
    except (binascii.Error, TypeError, ValueError) as exc:
        raise ValueError("camera image data is not base64: %s" % exc) from None
    frame = cv2.imdecode(np.frombuffer(raw, np.uint8), cv2.IMREAD_COLOR) if raw else None
    if frame is None:
        raise ValueError("camera image (%d bytes, %s) does not decode" % (len(raw), fmt))
    stamp = 0.0
    header = msg.get("header")
    if isinstance(header, dict) and isinstance(header.get("stamp"), dict):
        st = header["stamp"]
        try:
            stamp = float(st.get("secs", 0)) + 1e-9 * float(st.get("nsecs", 0))
        except (TypeError, ValueError):
            stamp = 0.0
    return stamp, frame


class RobotCameraSource:
    """Iterates over (time [s], BGR frame) of the robot's camera, newest frame first.

    Args:
        idle_timeout_s: stop iterating when no frame has come for this long (None: wait for
            ever, as for a webcam; :meth:`close` ends the iteration).

    Attributes:
        live: always True (the frames come in real time).
    """

    live = True

    def __init__(self, idle_timeout_s: float = None) -> None:
        """Create an empty source; frames come through :meth:`push`."""
        if idle_timeout_s is not None and not idle_timeout_s > 0:
            raise ValueError("idle_timeout_s must be > 0 or None")
        self.idle_timeout_s = idle_timeout_s
        self.fps = 0.0  # unknown until frames arrive; see stats()
        self._cond = threading.Condition()
        self._pending = None  # (receive wall time, message)
        self._closed = False
        self._t0 = None
        self._last_t = None
        self._yielded_stamp = 0.0
        self.received = 0
        self.dropped = 0
        self.bad = 0
        self.shown = 0
        self._first_rx = None
        self._last_rx = None
        self._first_shown = None
        self._last_shown = None
        self._transport_ms: list[float] = []
        self._done_ms: list[float] = []

    def push(self, msg: dict) -> None:
        """A camera message arrived (any thread; the link's callback)."""
        now = time.time()
        with self._cond:
            if self._closed:
                return
            if self._pending is not None:
                self.dropped += 1
            self._pending = (now, msg)
            self.received += 1
            self._first_rx = now if self._first_rx is None else self._first_rx
            self._last_rx = now
            self._cond.notify_all()

    def __iter__(self) -> "RobotCameraSource":
        """Iterate over frames."""
        return self

    def __next__(self) -> tuple[float, np.ndarray]:
        """The newest frame not seen yet; waits for one. StopIteration when closed or idle too long."""
        while True:
            with self._cond:
                deadline = None if self.idle_timeout_s is None else time.monotonic() + self.idle_timeout_s
                while self._pending is None and not self._closed:
                    left = None if deadline is None else deadline - time.monotonic()
                    if left is not None and left <= 0:
                        raise StopIteration
                    self._cond.wait(0.5 if left is None else min(0.5, left))
                if self._closed:
                    raise StopIteration
                rx, msg = self._pending
                self._pending = None
            try:
                stamp, frame = decode_compressed(msg)
            except ValueError as exc:  # a broken frame is skipped, never a crash
                self.bad += 1
                LOG.warning("robot camera frame skipped: %s", exc)
                continue
            now = time.time()
            if stamp <= 0:
                stamp = rx  # no camera stamp: the arrival time is the best there is
            if self._t0 is None:
                self._t0 = stamp
            t = stamp - self._t0
            if self._last_t is not None and t <= self._last_t:
                self.bad += 1  # an older frame (a reordered or repeated message) is not shown
                continue
            self._last_t = t
            self._yielded_stamp = stamp
            self.shown += 1
            self._first_shown = now if self._first_shown is None else self._first_shown
            self._last_shown = now
            self._transport_ms.append(1000.0 * (now - stamp))
            return t, frame

    def frame_done(self) -> None:
        """The pipeline is done with the last frame: records the stamp-to-result latency."""
        if self._yielded_stamp:
            self._done_ms.append(1000.0 * (time.time() - self._yielded_stamp))

    def stats(self) -> dict:
        """What came in and how fast.

        Returns:
            {"received", "shown", "dropped", "bad", "rx_fps", "shown_fps",
            "transport_ms": {"median", "p95", "max"}, "end_to_end_ms": {...}} (latencies from
            the camera stamp to the decoded frame, and to the pipeline's result).
        """

        def rate(n: int, first: float, last: float) -> float:
            return round((n - 1) / (last - first), 2) if n > 1 and last > first else 0.0

        def pct(values: list[float]) -> dict:
            if not values:
                return {"median": None, "p95": None, "max": None}
            v = np.asarray(values)
            return {"median": round(float(np.median(v)), 1), "p95": round(float(np.percentile(v, 95)), 1),
                    "max": round(float(v.max()), 1)}

        with self._cond:
            return {"received": self.received, "shown": self.shown, "dropped": self.dropped, "bad": self.bad,
                    "rx_fps": rate(self.received, self._first_rx, self._last_rx),
                    "shown_fps": rate(self.shown, self._first_shown, self._last_shown),
                    "transport_ms": pct(self._transport_ms), "end_to_end_ms": pct(self._done_ms)}

    def close(self) -> None:
        """End the iteration (a waiting ``next`` returns StopIteration)."""
        with self._cond:
            self._closed = True
            self._cond.notify_all()
