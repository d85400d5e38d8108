"""Sliding-window gesture recognition: key points per frame in, confident gestures out."""

from __future__ import annotations

import numpy as np

from rbd_local.gestures import checks, features, tracks
from rbd_local.gestures.model import NONE, GestureModel


class Decision:
    """What the recognizer concluded after one frame.

    Attributes:
        label: best class of the current window (``none`` below the threshold), or ``""``
            when there is no full window yet.
        confidence: probability of ``label``'s class (0 when there is no window).
        fired: True exactly when a gesture is to be sent for this frame.
        scores: {gesture: confidence} of every built-in and taught gesture, or None.
    """

    __slots__ = ("label", "confidence", "fired", "scores")

    def __init__(self, label: str = "", confidence: float = 0.0, fired: bool = False, scores: dict = None) -> None:
        """Create a decision."""
        self.label = label
        self.confidence = confidence
        self.fired = fired
        self.scores = scores

    def __repr__(self) -> str:
        """Readable form for logs."""
        return "Decision(%r, %.3f, fired=%s)" % (self.label, self.confidence, self.fired)


class GestureRecognizer:
    """Keeps the last ``window_s`` seconds of key points and classifies them every frame.

    Up to two hands are followed (:mod:`.tracks`); the one that performs (the farthest-travelled
    in its window) is classified, so a second, still hand changes nothing, and a jump of the
    detector from one hand to another starts a new track instead of looking like a swipe. A
    hand lost for up to ``max_gap_s`` (0.5 s: a fast, blurred hand) is bridged by
    straight-line interpolation between the frames before and after the loss.

    A gesture fires when the same class stays above the threshold for ``min_consecutive``
    frames and passes the checks of :mod:`.checks` (travel, swings, turns, the hand at rest);
    the motion a hand came into view with (an arm being raised) is replaced in the window by the
    hand held where it came to rest, and nothing fires before it came to rest; afterwards the
    window is cleared and nothing fires for ``cooldown_s`` seconds, so one performance sends one
    command.
    """

    def __init__(
        self,
        model: GestureModel,
        threshold: float = None,
        min_consecutive: int = 2,
        cooldown_s: float = 1.5,
        max_gap_s: float = tracks.MAX_GAP_S,
        min_fill: float = 0.9,
        min_seen: float = 0.5,
    ) -> None:
        """Create a recognizer.

        Args:
            model: the classifier.
            threshold: confidence threshold (default: the model's).
            min_consecutive: frames in a row above the threshold before firing (>= 1).
            cooldown_s: quiet time after a gesture fired [s].
            max_gap_s: longest bridged loss of a hand [s]; a longer one ends its track.
            min_fill: fraction of the window that must be covered by a track's frames.
            min_seen: fraction of the window's time with the hand actually seen (not bridged).

        Raises:
            ValueError: on out-of-range arguments.
        """
        thr = model.threshold if threshold is None else float(threshold)
        if not 0.0 < thr <= 1.0:
            raise ValueError("threshold must be in (0, 1], got %r" % threshold)
        if int(min_consecutive) < 1 or cooldown_s < 0 or max_gap_s <= 0 or not 0 < min_fill <= 1:
            raise ValueError("min_consecutive >= 1, cooldown_s >= 0, max_gap_s > 0, 0 < min_fill <= 1 required")
        self.model = model
        self.threshold = thr
        self.min_consecutive = int(min_consecutive)
        self.cooldown_s = float(cooldown_s)
        self.max_gap_s = float(max_gap_s)
        self.min_fill = float(min_fill)
        self.min_seen = float(min_seen)
        self.hands = tracks.HandTracks(self.max_gap_s)
        self.followed = None  # the track classified last (its newest key points: the overlay's hand)
        self.rejected = ""  # why the last gesture of the classifier was not believed
        self._last_t = None
        self._streak_label = NONE
        self._streak = 0
        self._quiet_until = -np.inf

    def reset(self) -> None:
        """Forget all buffered frames."""
        self.hands.reset()
        self.followed = None
        self._streak_label, self._streak = NONE, 0

    def update(self, t: float, keypoints: object, frame_size: tuple = None) -> Decision:
        """Add one frame and classify the current window.

        Args:
            t: frame time [s], increasing.
            keypoints: the frame's hands: None (no hand), one (21, 3) array in pixels, or a
                sequence / (H, 21, 3) array of them (NaN hands are ignored).
            frame_size: unused; kept for callers that pass the image size.

        Returns:
            The decision for this frame.
        """
        if self._last_t is not None and t <= self._last_t:
            self.reset()  # time went backwards (new clip): start over
        self._last_t = float(t)
        hands = tracks.as_hands(keypoints)
        self.hands.update(float(t), hands)
        if not hands:
            return Decision()
        window_s = self.model.window_s
        for tr in self.hands.tracks:
            tr.trim(t, window_s)
        track = tracks.performer(self.hands.tracks, float(t), window_s, self.min_fill)
        if track is None:
            return Decision()
        self.followed = track
        times = np.array(track.times)
        seen = np.diff(times)
        seen = float(np.minimum(seen, 0.1).sum())
        if seen < self.min_seen * window_s:
            return Decision()
        frames = np.array(track.frames)
        if track.settled_t is not None and times[0] < track.settled_t:
            # the motion the hand came into view with (an arm being raised) is no gesture: the
            # window sees the hand held where it came to rest until then
            k = int(np.searchsorted(times, track.settled_t))
            frames[:k] = frames[min(k, len(frames) - 1)]
        try:
            window = features.resample(times, frames, self.model.samples)
            label, conf, scores = self.model.classify(window, self.threshold)
            reason = checks.check(label, window, times[-1] - times[0]) if label in self.model.classes else ""
            if not reason and label != NONE and track.settled_t is None:
                reason = "the hand came into view moving (an arm being raised)"
        except ValueError:
            self.reset()  # degenerate key points: never a gesture
            return Decision()
        if reason:
            self.rejected = "%s: %s" % (label, reason)
            label = NONE
        if label != NONE and label == self._streak_label:
            self._streak += 1
        else:
            self._streak_label, self._streak = label, (1 if label != NONE else 0)
        fired = label != NONE and self._streak >= self.min_consecutive and t >= self._quiet_until
        if fired:
            self._quiet_until = t + self.cooldown_s
            self._restart_windows()
        return Decision(label, conf, fired, scores)

    def _restart_windows(self) -> None:
        """After a gesture: every window starts afresh, the hands stay known (not new arrivals)."""
        for tr in self.hands.tracks:
            tr.times, tr.frames = tr.times[-1:], tr.frames[-1:]
            tr.forget_entry()
        self._streak_label, self._streak = NONE, 0
