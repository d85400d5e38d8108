"""Teach mode: collect a visitor's shows of a new gesture and add it to the model.

:func:`extract_show` finds the one classifier window of a short recording that holds the
whole performance. :class:`TeachSession` is the live procedure the GUI and ``rbd-teach``
run, fed frame by frame with the detector's key points:

1. "get ready" (``ready_s``), then "show it now" for ``show_s`` seconds;
2. the show's window is extracted; a show without enough motion or with the hand lost is
   asked for again;
3. after ``shows`` good shows, :meth:`GestureModel.teach` adds the gesture (milliseconds),
   so it is recognised from the next frame on.

While a session runs the caller must not send gestures to the robot (the shows would be
recognised as whatever they resemble); the GUI pauses sending.
"""

import numpy as np

from rbd_local.gestures import features
from rbd_local.gestures.hand import MIDDLE_MCP, PALM, WRIST

MIN_SHOW_EXTENT = 0.6  # hand sizes: a palm that stays within this in the best window made no gesture
MAX_GAP_S = 0.25


def _path_stats(window: np.ndarray) -> tuple[float, float, float]:
    """Palm path length, extent (largest side of its bounding box) and motion centre.

    Lengths in hand sizes; the centre is the time of the motion's middle as a share of the window.
    """
    xy = window[:, :, :2]
    size = float(np.median(np.linalg.norm(xy[:, MIDDLE_MCP] - xy[:, WRIST], axis=1)))
    centre = xy[:, list(PALM)].mean(axis=1)
    steps = np.linalg.norm(np.diff(centre, axis=0), axis=1) / max(size, 1e-6)
    total = float(steps.sum())
    extent = float(np.ptp(centre, axis=0).max()) / max(size, 1e-6)
    if total <= 0:
        return 0.0, extent, 0.5
    mid = (np.arange(len(steps)) + 0.5) / len(steps)
    return total, extent, float((steps * mid).sum() / total)


def extract_show(times: np.ndarray, keypoints: np.ndarray, window_s: float, samples: int) -> np.ndarray | None:
    """The classifier window that holds one whole performance.

    Every window of ``window_s`` seconds ending at a frame, fully covered by frames with a
    hand (no gap longer than 0.25 s), is a candidate. The ones with the longest palm path
    (within 3 % of the longest) contain the whole motion; of those the one with the motion
    nearest its middle is returned.

    Args:
        times: (K,) frame times [s], increasing.
        keypoints: (K, 21, 3) key points, NaN where no hand was found.
        window_s: window length [s].
        samples: frames per window.

    Returns:
        (samples, 21, 3) window, or None when no window qualifies or the hand hardly moved
        (its palm stayed within :data:`MIN_SHOW_EXTENT` hand sizes).
    """
    times = np.asarray(times, dtype=np.float64)
    kp = np.asarray(keypoints, dtype=np.float64)
    ok = np.isfinite(kp.reshape(len(kp), -1)).all(axis=1)
    t, k = times[ok], kp[ok]
    if len(t) < 4:
        return None
    candidates = []
    start = 0
    for end in range(len(t)):
        while t[end] - t[start] > window_s + 1e-9:
            start += 1
        span = t[end] - t[start]
        if end - start + 1 < 4 or span < 0.9 * window_s:
            continue
        if np.any(np.diff(t[start:end + 1]) > MAX_GAP_S):
            continue
        try:
            w = features.resample(t[start:end + 1], k[start:end + 1], samples)
        except ValueError:
            continue
        length, extent, centre = _path_stats(w)
        candidates.append((length, abs(centre - 0.5), w, extent))
    if not candidates:
        return None
    best = max(c[0] for c in candidates)
    near = [c for c in candidates if c[0] >= 0.97 * best]
    chosen = min(near, key=lambda c: c[1])
    return chosen[2] if chosen[3] >= MIN_SHOW_EXTENT else None


class TeachSession:
    """The live teach procedure, driven by :meth:`feed` once per camera frame.

    Attributes:
        name, command: the gesture being taught and its trick.
        shows: number of shows wanted (3..5 recommended).
        windows: the good shows so far.
        phase: "ready", "show", "done" or "failed".
        message: what to tell the visitor now.
        result: the report of :meth:`GestureModel.teach` when done.
    """

    def __init__(self, model: object, name: str, command: str, shows: int = 5, ready_s: float = 1.5,
                 show_s: float = 2.0, max_attempts: int = 12, force: bool = False) -> None:
        """Start a session (the clock starts with the first fed frame).

        Args:
            model: the :class:`~rbd_local.gestures.model.GestureModel` to teach.
            name: the new gesture's name.
            command: the trick it triggers.
            shows: good shows needed (at least 3).
            ready_s: pause before each show [s].
            show_s: time given for each show [s] (must exceed the model's window).
            max_attempts: give up after this many shows (good or not).
            force: teach even when the shows look like a known gesture.

        Raises:
            ValueError: on bad arguments.
        """
        if int(shows) < 3:
            raise ValueError("a gesture needs at least 3 shows")
        if show_s < model.window_s:
            raise ValueError("show_s must be at least the model's window (%.1f s)" % model.window_s)
        if not name or name in model.classes:
            raise ValueError("%r cannot be taught: empty or a built-in class" % (name,))
        self.model = model
        self.name = name
        self.command = command
        self.shows = int(shows)
        self.ready_s = float(ready_s)
        self.show_s = float(show_s)
        self.max_attempts = int(max_attempts)
        self.force = bool(force)
        self.windows: list[np.ndarray] = []
        self.attempts = 0
        self.phase = "ready"
        self.message = "get ready: show %d of %d" % (1, self.shows)
        self.result = None
        self._phase_t = None
        self._times: list[float] = []
        self._kps: list[np.ndarray] = []

    @property
    def active(self) -> bool:
        """True until the session is done or failed."""
        return self.phase in ("ready", "show")

    def feed(self, t: float, keypoints: np.ndarray | None) -> str:
        """Advance with one frame.

        Args:
            t: frame time [s].
            keypoints: (21, 3) key points, or None without a hand.

        Returns:
            The current phase.
        """
        if not self.active:
            return self.phase
        if self._phase_t is None:
            self._phase_t = t
        if self.phase == "ready":
            if t - self._phase_t >= self.ready_s:
                self.phase, self._phase_t = "show", t
                self._times, self._kps = [], []
                self.message = "show %d of %d: perform the gesture now" % (len(self.windows) + 1, self.shows)
            return self.phase
        self._times.append(float(t))
        self._kps.append(np.full((21, 3), np.nan) if keypoints is None else np.asarray(keypoints, dtype=np.float64))
        if t - self._phase_t >= self.show_s:
            self._finish_show(t)
        return self.phase

    def _finish_show(self, t: float) -> None:
        self.attempts += 1
        w = extract_show(np.array(self._times), np.array(self._kps), self.model.window_s, self.model.samples)
        if w is None:
            note = "no gesture seen (hand lost or hardly moving): again"
        else:
            self.windows.append(w)
            note = "show %d of %d recorded" % (len(self.windows), self.shows)
        if len(self.windows) >= self.shows:
            try:
                self.result = self.model.teach(self.name, self.command, np.stack(self.windows), force=self.force)
            except ValueError as exc:  # TeachConflictError included
                self.phase, self.message = "failed", "not taught: %s" % exc
                return
            self.phase = "done"
            self.message = "taught %r -> %s from %d shows" % (self.name, self.command, len(self.windows))
            return
        if self.attempts >= self.max_attempts:
            self.phase, self.message = "failed", "not taught: only %d good shows in %d attempts" % (
                len(self.windows), self.attempts)
            return
        self.phase, self._phase_t = "ready", t
        self.message = "%s; get ready: show %d of %d" % (note, len(self.windows) + 1, self.shows)
