"""Frame -> key points -> window -> gesture -> command, with the overlay, for one video stream."""

from __future__ import annotations

import logging
import time
from typing import Callable

import numpy as np

from rbd_local.gestures.config import check_mapping
from rbd_local.gestures.detector import HandDetector
from rbd_local.gestures.model import GestureModel
from rbd_local.gestures.overlay import draw_overlay
from rbd_local.gestures.recognizer import Decision, GestureRecognizer

LOG = logging.getLogger("rbd_local.gestures")


class FrameResult:
    """Outcome of one frame: key points, decision, the command sent (or ""), timings."""

    __slots__ = ("keypoints", "decision", "command", "detect_ms", "classify_ms")

    def __init__(self, keypoints: np.ndarray | None, decision: Decision, command: str, detect_ms: float,
                 classify_ms: float) -> None:
        """Bundle the results."""
        self.keypoints = keypoints
        self.decision = decision
        self.command = command
        self.detect_ms = detect_ms
        self.classify_ms = classify_ms


class GesturePipeline:
    """Runs detection and recognition on frames and hands confident gestures to ``send``.

    ``send`` is any callable taking the trick command (the robot link's ``send_gesture`` in
    the app, a list's ``append`` in tests); it must not block.
    """

    def __init__(
        self,
        model: GestureModel,
        mapping: dict,
        send: Callable[[str], object] = None,
        detector: HandDetector = None,
        threshold: float = None,
        min_consecutive: int = 2,
        cooldown_s: float = 1.5,
        model_complexity: int = 0,
    ) -> None:
        """Create the pipeline.

        Args:
            model: gesture classifier.
            mapping: gesture class -> trick command.
            send: called with the command of every fired gesture (None: only report).
            detector: hand detector (default: a tracking MediaPipe detector).
            threshold: confidence threshold (default: the model's).
            min_consecutive: frames above threshold before firing.
            cooldown_s: quiet time after a fired gesture [s].
            model_complexity: MediaPipe model when the detector is created here.

        Raises:
            ValueError: if the mapping names classes the model lacks.
        """
        self.unmapped = check_mapping(mapping, model.classes + model.taught.names)
        self.mapping = dict(mapping)
        self.model = model
        self.teach = None
        self.send = send
        self.detector = detector if detector is not None else HandDetector(model_complexity=model_complexity)
        self.recognizer_args = (threshold, min_consecutive, cooldown_s)
        self.recognizer = GestureRecognizer(model, threshold, min_consecutive, cooldown_s)
        self.last_sent = ""
        self.last_gesture = ("", 0.0)

    def process(self, t: float, frame: np.ndarray) -> FrameResult:
        """Run one frame through the pipeline.

        Args:
            t: frame time [s].
            frame: BGR image.

        Returns:
            What was seen and decided.
        """
        t0 = time.perf_counter()
        try:
            if hasattr(self.detector, "detect_hands"):
                hands = [pts for pts, _score in self.detector.detect_hands(frame)]
            else:  # a detector of one hand per frame (tests' stand-ins)
                found = self.detector.detect(frame)
                hands = [found[0]] if found is not None else []
        except ValueError as exc:  # a broken frame counts as "no hand", never a crash
            LOG.warning("frame skipped: %s", exc)
            hands = []
        t1 = time.perf_counter()
        keypoints = hands[0] if hands else None
        if self.teach is not None and self.teach.active:
            # teach mode: the shows feed the session; nothing is recognised or sent meanwhile
            self.teach.feed(t, hands)
            if not self.teach.active:
                self.recognizer.reset()
            return FrameResult(keypoints, Decision(), "", 1000 * (t1 - t0), 1000 * (time.perf_counter() - t1))
        decision = self.recognizer.update(t, hands)
        followed = self.recognizer.followed
        if followed is not None and followed.last_t == t and len(hands) > 1:
            keypoints = followed.frames[-1]  # the overlay shows the hand that performs
        t2 = time.perf_counter()
        command = ""
        if decision.fired:
            command = self.command_of(decision.label)
            self.last_gesture = (decision.label, decision.confidence)
            if command:
                self.last_sent = command
                if self.send is not None:
                    self.send(command)
        return FrameResult(keypoints, decision, command, 1000 * (t1 - t0), 1000 * (t2 - t1))

    def command_of(self, label: str) -> str:
        """The trick of a gesture: a taught gesture's own trick, else the configured mapping ("" if none)."""
        return self.model.taught.commands.get(label) or self.mapping.get(label, "")

    def start_teach(self, session: object) -> None:
        """Run a :class:`~rbd_local.gestures.teach.TeachSession` on the next frames (sending pauses)."""
        self.teach = session
        self.recognizer.reset()

    def replace_model(self, model: GestureModel) -> None:
        """Use another model from the next frame on (e.g. the model file after an undo).

        Raises:
            ValueError: if the mapping names classes the new model lacks.
        """
        self.unmapped = check_mapping(self.mapping, model.classes + model.taught.names)
        self.model = model
        self.recognizer = GestureRecognizer(model, *self.recognizer_args)

    def annotate(self, frame: np.ndarray, result: FrameResult) -> np.ndarray:
        """The audience view of ``frame``: skeleton, class and confidence, taught gestures, last command sent."""
        taught = [(n, self.model.taught.commands[n]) for n in self.model.taught.names]
        teaching = self.teach.message if self.teach is not None and self.teach.active else ""
        return draw_overlay(frame, result.keypoints, result.decision.label, result.decision.confidence,
                            self.last_sent, scores=result.decision.scores, taught=taught, teaching=teaching)

    def close(self) -> None:
        """Release the detector."""
        self.detector.close()
