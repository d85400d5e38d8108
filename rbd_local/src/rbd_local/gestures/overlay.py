"""The audience view: key points, skeleton, class and confidence drawn on the frame."""

from __future__ import annotations

import numpy as np

from rbd_local.gestures.hand import HAND_CONNECTIONS

SKELETON_BGR = (255, 200, 0)
POINT_BGR = (0, 0, 255)
FIRED_BGR = (0, 200, 0)
TEXT_BGR = (255, 255, 255)
TAUGHT_BGR = (0, 170, 255)


def draw_overlay(
    frame: np.ndarray, keypoints: np.ndarray | None, label: str, confidence: float, sent: str = "",
    scores: dict = None, taught: list = None, teaching: str = "",
) -> np.ndarray:
    """Draw the hand and the classifier's view on a copy of ``frame``.

    Args:
        frame: BGR image.
        keypoints: (21, 2|3) key points in pixels, or None.
        label: current class ("" while the window fills).
        confidence: its probability.
        sent: the command last sent (shown highlighted), or "".
        scores: {gesture: confidence} of the current window (bars for the taught gestures).
        taught: [(gesture, trick)] of the taught gestures, listed at the bottom left.
        teaching: teach-mode instruction shown across the frame ("" when not teaching).

    Returns:
        The annotated image.
    """
    import cv2

    out = frame.copy()
    if keypoints is not None:
        pts = np.round(np.asarray(keypoints)[:, :2]).astype(int)
        for a, b in HAND_CONNECTIONS:
            cv2.line(out, tuple(int(v) for v in pts[a]), tuple(int(v) for v in pts[b]), SKELETON_BGR, 2, cv2.LINE_AA)
        for p in pts:
            cv2.circle(out, (int(p[0]), int(p[1])), 4, POINT_BGR, -1, cv2.LINE_AA)
    text = "no hand" if keypoints is None else ("..." if not label else "%s %.0f%%" % (label, 100 * confidence))
    cv2.rectangle(out, (0, 0), (out.shape[1], 34), (40, 40, 40), -1)
    cv2.putText(out, text, (8, 24), cv2.FONT_HERSHEY_SIMPLEX, 0.8, TEXT_BGR, 2, cv2.LINE_AA)
    if sent:
        cv2.putText(out, "sent: " + sent, (out.shape[1] // 2, 24), cv2.FONT_HERSHEY_SIMPLEX, 0.8, FIRED_BGR, 2,
                    cv2.LINE_AA)
    if taught:
        h = out.shape[0]
        top = h - 8 - 22 * len(taught)
        cv2.rectangle(out, (0, top - 24), (300, h), (40, 40, 40), -1)
        cv2.putText(out, "taught gestures", (8, top - 6), cv2.FONT_HERSHEY_SIMPLEX, 0.55, TEXT_BGR, 1, cv2.LINE_AA)
        for i, (name, trick) in enumerate(taught):
            y = top + 22 * i + 16
            conf = float((scores or {}).get(name, 0.0))
            cv2.rectangle(out, (200, y - 12), (200 + int(90 * conf), y), TAUGHT_BGR, -1)
            cv2.rectangle(out, (200, y - 12), (290, y), TEXT_BGR, 1)
            cv2.putText(out, "%s -> %s" % (name, trick), (8, y), cv2.FONT_HERSHEY_SIMPLEX, 0.5, TEXT_BGR, 1,
                        cv2.LINE_AA)
    if teaching:
        w = out.shape[1]
        cv2.rectangle(out, (0, 40), (w, 84), (0, 90, 160), -1)
        cv2.putText(out, "TEACH: " + teaching, (8, 70), cv2.FONT_HERSHEY_SIMPLEX, 0.6, TEXT_BGR, 2, cv2.LINE_AA)
    return out
