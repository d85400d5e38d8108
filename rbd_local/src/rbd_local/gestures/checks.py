"""Plain checks a window must pass before the classifier's gesture is believed (issue 26).

The logistic regression sees features of the whole window; on real footage it was fooled by
motions with the right general direction but not the gesture's substance. Each check asks for
that substance, in units of the hand's own size (wrist to middle-finger base; a hand length,
wrist to fingertip, is :data:`HAND_LENGTH` of them):

- ``swipe_right`` / ``push_down``: the palm travels at least :data:`MIN_TRAVEL` hand lengths
  the gesture's way (a drifting or closing hand moves less), and the hand has come to rest at
  the window's end (an arm lowered out of the frame never rests: no ``push_down``);
- ``wave``: the hand swings back and forth at least twice (:data:`MIN_SWINGS`), by the palm's
  side-to-side motion or by its turn about the wrist (a wave from the wrist barely moves the
  palm) -- a one-way swipe left is no wave;
- ``circle``: the palm's heading turns by at least :data:`MIN_TURNS` of a full turn in one
  sense (loose arm arcs turn much less, or back and forth);
- every gesture, built-in or taught: the motion a hand came into view with (an arm being
  raised) is no gesture: the recognizer replaces that part of a window by the hand held where it
  came to rest (:class:`~rbd_local.gestures.tracks.Track`'s ``settled_t``), and gives nothing
  while the hand has not yet come to rest.
"""

import numpy as np

from rbd_local.gestures import features

#: A hand length (wrist to middle fingertip) in hand sizes (wrist to middle-finger base).
HAND_LENGTH = 2.0
#: Least travel of a swipe or push [hand lengths].
MIN_TRAVEL = 1.0
#: Largest palm motion over the window's last :data:`REST_S` for a swipe or push to count as ended [hand sizes].
REST_MOTION = 0.4
#: The time over which the hand must have come to rest [s].
REST_S = 0.12
#: Least number of swings back for a wave.
MIN_SWINGS = 2
#: Palm swing of a wave, from one extreme to the next [hand sizes], and the hand's turn about the
#: wrist [deg]. A palm wave swings the forearm about the elbow (or the arm about the shoulder) and
#: sweeps the hand by about its own size or more (both clip generators: 1-3 hand sizes); a smaller
#: back-and-forth of the palm is a wandering hand (issue 26: 0.35-0.5 hand sizes fired 'wave' at
#: low resolution) -- a small real wave is a wave from the wrist, which the turn counts.
SWING_PALM = 0.7
SWING_TURN_DEG = 12.0
#: Least net heading turn of a circle [turns].
MIN_TURNS = 0.6


def turning(path: np.ndarray, min_step: float = 0.05) -> float:
    """Net turn of a path's heading [turns], counting only steps longer than ``min_step``."""
    steps = np.diff(path, axis=0)
    moving = np.linalg.norm(steps, axis=1) > min_step
    heading = np.arctan2(steps[moving, 1], steps[moving, 0])
    if len(heading) < 2:
        return 0.0
    turns = (np.diff(heading) + np.pi) % (2 * np.pi) - np.pi
    return float(turns.sum() / (2 * np.pi))


def wave_swings(window: np.ndarray) -> int:
    """Swings back of a wave: the more of the palm's side-to-side swings and the hand's turns about the wrist."""
    path, _ = features.palm_path(window)
    return max(features.swings(path[:, 0], SWING_PALM),
               features.swings(features.swing_angle(window), np.deg2rad(SWING_TURN_DEG)))


def check(label: str, window: np.ndarray, window_s: float) -> str:
    """Why a built-in gesture is not believed for this window ("" when it passes).

    Args:
        label: the classifier's gesture (labels without a check pass).
        window: (T, 21, 3) key points, evenly spaced over ``window_s``.
        window_s: the window's length [s].

    Returns:
        "" or a short reason.
    """
    if label in ("swipe_right", "push_down"):
        path, _ = features.palm_path(window)
        axis = 0 if label == "swipe_right" else 1
        travel = float(path[-1, axis] - path[:, axis].min())
        if travel < MIN_TRAVEL * HAND_LENGTH:
            return "travel %.1f hand lengths < %.1f" % (travel / HAND_LENGTH, MIN_TRAVEL)
        tail = max(2, int(np.ceil(REST_S / window_s * (len(path) - 1))) + 1)
        end = path[-tail:]
        if float(np.linalg.norm(end[-1] - end[0])) > REST_MOTION:
            return "hand still moving at the end"
    elif label == "wave":
        n = wave_swings(window)
        if n < MIN_SWINGS:
            return "%d swings < %d" % (n, MIN_SWINGS)
    elif label == "circle":
        path, _ = features.palm_path(window)
        turns = abs(turning(path))
        if turns < MIN_TURNS:
            return "turned %.2f < %.2f" % (turns, MIN_TURNS)
    return ""
