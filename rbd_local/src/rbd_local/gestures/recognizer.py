"""Sliding-window gesture recognition: key points per frame in, confident gestures out."""

from __future__ import annotations

import collections

import numpy as np

from rbd_local.gestures import features
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

    A gesture fires when the same class stays above the threshold for ``min_consecutive``
    frames; afterwards the window is cleared and nothing fires for ``cooldown_s`` seconds, so
    one performance sends one command. A hand that disappears for longer than ``max_gap_s``
    clears the window (a gesture must be seen whole).
    """

    def __init__(
        self,
        model: GestureModel,
        threshold: float = None,
        min_consecutive: int = 2,
        cooldown_s: float = 1.5,
        max_gap_s: float = 0.25,
        min_fill: float = 0.9,
    ) -> None:
        """Create a recognizer.

        Args:
            model: the classifier.
            threshold: confidence threshold (default: the model's).
            min_consecutive: frames in a row above the threshold before firing (>= 1).
            cooldown_s: quiet time after a gesture fired [s].
            max_gap_s: longest tolerated stretch without a hand [s].
            min_fill: fraction of the window that must be covered by frames before classifying.

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
        self._times: collections.deque = collections.deque()
        self._frames: collections.deque = collections.deque()
        self._streak_label = NONE
        self._streak = 0
        self._quiet_until = -np.inf

    def reset(self) -> None:
        """Forget all buffered frames."""
        self._times.clear()
        self._frames.clear()
        self._streak_label, self._streak = NONE, 0

    def update(self, t: float, keypoints: np.ndarray | None) -> Decision:
        """Add one frame and classify the current window.

        Args:
            t: frame time [s], increasing.
            keypoints: (21, 3) key points in pixels, or None when no hand was found.

        Returns:
            The decision for this frame.
        """
        if self._times and t <= self._times[-1]:
            self.reset()  # time went backwards (new clip): start over
        if keypoints is None or not np.all(np.isfinite(keypoints)):
            if self._times and t - self._times[-1] > self.max_gap_s:
                self.reset()
            return Decision()
        if self._times and t - self._times[-1] > self.max_gap_s:
            self.reset()
        self._times.append(float(t))
        self._frames.append(np.asarray(keypoints, dtype=np.float64))
        while len(self._times) > 2 and t - self._times[1] >= self.model.window_s:
            self._times.popleft()
            self._frames.popleft()
        span = self._times[-1] - self._times[0]
        if span < self.min_fill * self.model.window_s or len(self._times) < 4:
            return Decision()
        try:
            window = features.resample(np.array(self._times), np.array(self._frames), self.model.samples)
            label, conf, scores = self.model.classify(window, self.threshold)
        except ValueError:
            self.reset()  # degenerate key points: never a gesture
            return Decision()
        if label != NONE and label == self._streak_label:
            self._streak += 1
        else:
            self._streak_label, self._streak = label, (1 if label != NONE else 0)
        fired = label != NONE and self._streak >= self.min_consecutive and t >= self._quiet_until
        if fired:
            self._quiet_until = t + self.cooldown_s
            self.reset()
        return Decision(label, conf, fired, scores)
