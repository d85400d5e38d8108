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

:class:`TeachDesk` runs sessions for an app whose pipeline has a thread of its own (the
GUI's Teach panel) and keeps the model file: saved after each change with the previous file
kept (:func:`restore_previous` undoes one step).
"""

from __future__ import annotations

import os
import threading

import numpy as np

from rbd_local.gestures import features, tracks
from rbd_local.gestures.model import GestureModel

MIN_SHOW_EXTENT = 0.6  # hand sizes: a palm that stays within this in the best window made no gesture
MAX_GAP_S = tracks.MAX_GAP_S  # the recognizer's: a loss of the hand up to this is bridged


def _path_stats(window: np.ndarray) -> tuple[float, float, float]:
    """Palm path length, extent (largest side of its bounding box) and motion centre.

    Lengths in hand sizes; the centre is the time of the motion's middle as a share of the window.
    """
    path, _ = features.palm_path(window)
    steps = np.linalg.norm(np.diff(path, axis=0), axis=1)
    total = float(steps.sum())
    extent = float(np.ptp(path, axis=0).max())
    if total <= 0:
        return 0.0, extent, 0.5
    mid = (np.arange(len(steps)) + 0.5) / len(steps)
    return total, extent, float((steps * mid).sum() / total)


def extract_show(times: np.ndarray, keypoints: np.ndarray, window_s: float, samples: int) -> np.ndarray | None:
    """The classifier window that holds one whole performance.

    The hands are followed as the recognizer follows them (:func:`tracks.split_tracks`: up to
    two hands, a loss of up to :data:`MAX_GAP_S` bridged). Every window of ``window_s``
    seconds ending at a frame of a track, covered by its frames without a longer loss, is a
    candidate. The ones with the longest palm path (within 3 % of the longest, over every
    track: the hand that performs) contain the whole motion; of those the one with the motion
    nearest its middle is returned.

    Args:
        times: (K,) frame times [s], increasing.
        keypoints: (K, 21, 3) key points of one hand or (K, H, 21, 3) of up to H hands, NaN
            where no hand was found.
        window_s: window length [s].
        samples: frames per window.

    Returns:
        (samples, 21, 3) window, or None when no window qualifies or the hand hardly moved
        (its palm stayed within :data:`MIN_SHOW_EXTENT` hand sizes).
    """
    candidates = []
    for t, k in tracks.split_tracks(times, keypoints, MAX_GAP_S):
        if len(t) < 4:
            continue
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
                length, extent, centre = _path_stats(w)
            except ValueError:  # too few frames, or a zero-size hand
                continue
            candidates.append((length, abs(centre - 0.5), w, extent))
    if not candidates:
        return None
    best = max(c[0] for c in candidates)
    near = [c for c in candidates if c[0] >= 0.97 * best]
    chosen = min(near, key=lambda c: c[1])
    return chosen[2] if chosen[3] >= MIN_SHOW_EXTENT else None


def show_problem(times: np.ndarray, keypoints: np.ndarray, window_s: float) -> str:
    """Why a show gave no usable window (for the visitor), given that :func:`extract_show` found none.

    Args:
        times: (K,) frame times [s].
        keypoints: (K, 21, 3) or (K, H, 21, 3) key points, NaN without a hand.
        window_s: the model's window [s].
    """
    kp = np.asarray(keypoints, dtype=np.float64)
    if kp.ndim == 3:
        kp = kp[:, None]
    found = np.isfinite(kp[:, :, 0, 0]).any(axis=1) if len(kp) else np.zeros(0, bool)
    if not found.any():
        return "no hand seen"
    longest = max((len(t) and t[-1] - t[0]) for t, _k in tracks.split_tracks(times, kp, MAX_GAP_S))
    if longest < 0.9 * window_s:
        return "hand seen for only %.1f s in one piece (lost for more than %.1f s; %.0f %% of frames)" % (
            longest, MAX_GAP_S, 100.0 * found.mean())
    return "the hand hardly moved"


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
        self.unusable = 0
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

    def feed(self, t: float, keypoints: object) -> str:
        """Advance with one frame.

        Args:
            t: frame time [s].
            keypoints: the frame's hands (None, one (21, 3) array or a list of them).

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
        hands = tracks.as_hands(keypoints)[:2]
        frame = np.full((2, 21, 3), np.nan)
        for i, h in enumerate(hands):
            frame[i] = h[:, :3] if h.shape[1] >= 3 else np.pad(h, ((0, 0), (0, 3 - h.shape[1])))
        self._kps.append(frame)
        if t - self._phase_t >= self.show_s:
            self._finish_show(t)
        return self.phase

    def _finish_show(self, t: float) -> None:
        self.attempts += 1
        kps = np.array(self._kps)
        w = extract_show(np.array(self._times), kps, self.model.window_s, self.model.samples)
        if w is None:
            self.unusable += 1
            note = "show not usable: %s; again" % show_problem(np.array(self._times), kps, self.model.window_s)
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


def restore_previous(path: str) -> None:
    """Put the model file back as it was before its last change (one step of undo).

    ``GestureModel.save(path, keep_previous=True)`` keeps the replaced file as ``path.prev``;
    this moves it back.

    Raises:
        FileNotFoundError: when there is nothing to undo (no ``path.prev``).
    """
    prev = path + ".prev"
    if not os.path.isfile(prev):
        raise FileNotFoundError("nothing to undo (%s missing)" % prev)
    os.replace(prev, path)


class TeachDesk:
    """Teach mode for an app whose gesture pipeline runs in a thread of its own (the GUI).

    The UI thread calls :meth:`start`, :meth:`cancel`, :meth:`forget`, :meth:`undo` and reads
    :meth:`status`; they only leave requests. The gesture thread calls :meth:`step` with its
    :class:`~rbd_local.gestures.pipeline.GesturePipeline` before every frame; there the
    requests are carried out: a session is handed to the pipeline (which then sends nothing
    until the session ends), a finished session's gesture is saved to the model file (the old
    file kept for :meth:`undo`), a forgotten gesture is removed, an undone file is loaded.

    Args:
        model_path: the model file teach mode writes (``cfg["teach_model"]``).
        session_kwargs: extra arguments of every :class:`TeachSession` (e.g. ``ready_s``).
    """

    def __init__(self, model_path: str, **session_kwargs: object) -> None:
        """Create the desk (no session yet)."""
        if not model_path:
            raise ValueError("model_path must be a file name")
        self.model_path = model_path
        self.session_kwargs = session_kwargs
        self._lock = threading.Lock()
        self._requests: list = []
        self._session = None
        self._status = {"phase": "idle", "message": "", "name": "", "trick": "", "good": 0, "shows": 0,
                        "revision": 0, "taught": []}
        self.errors: list[str] = []

    # ------------------------------------------------------------- UI thread
    def start(self, name: str, trick: str, shows: int = 5) -> None:
        """Ask for a teach session (it begins with the next frame).

        Raises:
            ValueError: on an empty name or trick, fewer than 3 shows, or while a session runs.
        """
        name, trick = (name or "").strip(), (trick or "").strip()
        if not name or not trick:
            raise ValueError("a gesture name and a trick are needed")
        if not name.replace("_", "").isalnum():
            raise ValueError("gesture names use letters, digits and _ only: %r" % name)
        if int(shows) < 3:
            raise ValueError("a gesture needs at least 3 shows")
        with self._lock:
            if self._status["phase"] in ("starting", "ready", "show"):
                raise ValueError("a teach session is already running")
            self._status.update(phase="starting", message="starting…", name=name, trick=trick, good=0,
                                shows=int(shows))
            self._requests.append(("start", (name, trick, int(shows))))

    def cancel(self) -> None:
        """Stop a running session without teaching anything."""
        with self._lock:
            self._requests.append(("cancel", None))

    def forget(self, name: str) -> None:
        """Ask to remove a taught gesture (saved; undo brings it back)."""
        with self._lock:
            self._requests.append(("forget", name))

    def undo(self) -> None:
        """Ask to restore the model file before its last change."""
        with self._lock:
            self._requests.append(("undo", None))

    def status(self) -> dict:
        """A copy of the current state.

        Returns:
            {"phase": idle | starting | ready | show | done | failed, "message", "name",
            "trick", "good" (good shows so far), "shows" (wanted), "revision",
            "taught": [(gesture, trick, shows)]}.
        """
        with self._lock:
            out = dict(self._status)
            out["taught"] = list(out["taught"])
            return out

    # -------------------------------------------------------- gesture thread
    def step(self, pipeline: object) -> None:
        """Carry out pending requests and follow the session; call before each frame.

        Args:
            pipeline: the app's :class:`~rbd_local.gestures.pipeline.GesturePipeline`.
        """
        with self._lock:
            requests, self._requests = self._requests, []
        for kind, arg in requests:
            try:
                self._do(pipeline, kind, arg)
            except (OSError, ValueError, KeyError) as exc:
                text = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
                self.errors.append(text)
                self._set(phase="failed", message=str(text))
        session = self._session
        if session is not None and not session.active:
            self._session = None
            self._set(good=len(session.windows))
            if session.phase == "done":
                try:
                    pipeline.model.save(self.model_path, keep_previous=True)
                    self._set(phase="done", message=session.message + "; saved")
                except OSError as exc:  # taught for this run, but it will not survive a restart
                    self._set(phase="failed", message="%s, but NOT saved: %s" % (session.message, exc))
            else:
                self._set(phase="failed", message=session.message)
        elif session is not None:
            self._set(phase=session.phase, message=session.message, good=len(session.windows))
        self._set(revision=pipeline.model.revision, taught=[
            (n, pipeline.model.taught.commands[n], len(pipeline.model.taught.windows[n]))
            for n in pipeline.model.taught.names])

    def _do(self, pipeline: object, kind: str, arg: object) -> None:
        if kind == "start":
            name, trick, shows = arg
            session = TeachSession(pipeline.model, name, trick, shows=shows, **self.session_kwargs)
            self._session = session
            pipeline.start_teach(session)
            self._set(phase=session.phase, message=session.message, good=0)
        elif kind == "cancel":
            if self._session is not None:
                self._session.phase = "failed"
                self._session.message = "cancelled: nothing taught"
        elif kind == "forget":
            pipeline.model.forget(arg)
            pipeline.model.save(self.model_path, keep_previous=True)
            self._set(phase="idle", message="forgot %r; saved" % arg)
        elif kind == "undo":
            restore_previous(self.model_path)
            pipeline.replace_model(GestureModel.load(self.model_path))
            self._set(phase="idle", message="undone: model revision %d" % pipeline.model.revision)

    def _set(self, **values: object) -> None:
        with self._lock:
            self._status.update(values)
