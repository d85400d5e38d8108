"""Robustness evaluation on clips made from real hand photos (used by tests and ``rbd-evaluate``).

A clip (:mod:`rbd_local.gestures.realclips`) is rendered, run through MediaPipe Hands once
(the slow part), and its key points are kept; the recogniser (the same
:class:`~rbd_local.gestures.recognizer.GestureRecognizer` the app runs after the detector)
is then replayed over the key points for every model to score, so a model taught from some
clips is scored on others without running MediaPipe again.
"""

import hashlib
import os

import numpy as np

from rbd_local.compat import zip_strict
from rbd_local.gestures import realclips
from rbd_local.gestures.model import NONE, GestureModel
from rbd_local.gestures.recognizer import GestureRecognizer
from rbd_local.gestures.teach import extract_show


class Clip:
    """One tracked clip: what it shows, its frame times and key points (NaN: no hand)."""

    __slots__ = ("kind", "times", "keypoints", "condition")

    def __init__(self, kind: str, times: np.ndarray, keypoints: np.ndarray, condition: str) -> None:
        """Bundle a clip's data; ``keypoints`` (K, 21, 3) of one hand or (K, H, 21, 3) of H hands."""
        self.kind = kind
        self.times = np.asarray(times, dtype=np.float64)
        kp = np.asarray(keypoints, dtype=np.float64)
        self.keypoints = kp[:, None] if kp.ndim == 3 else kp
        self.condition = condition

    def found(self) -> np.ndarray:
        """(K,) whether a hand was found in each frame."""
        return np.isfinite(self.keypoints[:, :, 0, 0]).any(axis=1)

    @property
    def detected(self) -> int:
        """Frames in which a hand was found."""
        return int(self.found().sum())

    @property
    def seconds(self) -> float:
        """The clip's length [s] (one frame interval after its last frame included)."""
        if len(self.times) < 2:
            return 0.0
        return float(self.times[-1] - self.times[0] + np.median(np.diff(self.times)))

    def longest_gap(self) -> float:
        """The longest time without a hand between the first and the last frame with one [s]."""
        found = np.flatnonzero(self.found())
        if len(found) < 2:
            return 0.0
        return float(np.diff(np.asarray(self.times)[found]).max() - np.median(np.diff(self.times)))


def load_sprites(photo_paths: list[str]) -> list:
    """Hand sprites of the real photos (see :class:`~rbd_local.gestures.photo_clip.HandSprite`)."""
    import cv2

    from rbd_local.gestures.photo_clip import HandSprite

    return [HandSprite(cv2.imread(p)) for p in photo_paths]


def make_clips(sprites: list, plan: dict, cond: realclips.Condition, seed: int, detector: object) -> list[Clip]:
    """Render and track clips.

    Args:
        sprites: hand sprites.
        plan: motion kind -> number of clips.
        cond: viewing condition.
        seed: random seed (same seed, same clips).
        detector: a video-mode :class:`~rbd_local.gestures.detector.HandDetector`.

    Returns:
        The tracked clips, in plan order.
    """
    rng = np.random.default_rng(seed)
    out = []
    for kind, count in plan.items():
        for _ in range(int(count)):
            times, frames = realclips.make_clip(sprites, kind, cond, rng)
            out.append(Clip(kind, times, realclips.track_clip(detector, frames), cond.name))
    return out


def save_clips(path: str, clips: list[Clip]) -> None:
    """Write tracked clips to an ``.npz`` file (no pickles), atomically."""
    data = {"kinds": np.array([c.kind for c in clips], dtype=str).reshape(-1),
            "conditions": np.array([c.condition for c in clips], dtype=str).reshape(-1)}
    for i, c in enumerate(clips):
        data["times%d" % i] = np.asarray(c.times, dtype=np.float64)
        data["keypoints%d" % i] = np.asarray(c.keypoints, dtype=np.float64)
    tmp = path + ".part"
    with open(tmp, "wb") as fh:
        np.savez_compressed(fh, **data)
    os.replace(tmp, path)


def load_clips(path: str) -> list[Clip]:
    """Read clips written by :func:`save_clips`."""
    with np.load(path, allow_pickle=False) as data:
        return [Clip(str(k), data["times%d" % i], data["keypoints%d" % i], str(c))
                for i, (k, c) in enumerate(zip_strict(data["kinds"], data["conditions"]))]


def cached_clips(cache_dir: str, key: str, make: object) -> list[Clip]:
    """The clips stored under ``key`` in ``cache_dir``, or ``make()``'s, stored there first.

    Args:
        cache_dir: directory of the cache ("" or None: no cache, always ``make()``).
        key: everything the clips depend on (hashed into the file name).
        make: callable returning the tracked clips.
    """
    if not cache_dir:
        return make()
    os.makedirs(cache_dir, exist_ok=True)
    path = os.path.join(cache_dir, "clips-%s.npz" % hashlib.sha256(key.encode()).hexdigest()[:20])
    if os.path.isfile(path):
        return load_clips(path)
    clips = make()
    save_clips(path, clips)
    return clips


def replay(model: GestureModel, clip: Clip, min_consecutive: int = 2, cooldown_s: float = 1.5,
           threshold: float = None) -> tuple[list[str], list[str]]:
    """Run the recogniser over a clip's key points.

    Returns:
        (labels that fired, in order; the decided label of every full window).
    """
    rec = GestureRecognizer(model, threshold, min_consecutive, cooldown_s)
    fired, windows = [], []
    for t, kp in zip_strict(clip.times, clip.keypoints):
        d = rec.update(float(t), kp)
        if d.label:
            windows.append(d.label)
        if d.fired:
            fired.append(d.label)
    return fired, windows


def show_windows(model: GestureModel, clips: list[Clip]) -> np.ndarray:
    """One show window per clip (clips without a usable show are skipped)."""
    out = [extract_show(c.times, c.keypoints, model.window_s, model.samples) for c in clips]
    out = [w for w in out if w is not None]
    return np.stack(out) if out else np.empty((0, model.samples, 21, 3))


def score(model: GestureModel, clips: list[Clip], expected: dict) -> dict:
    """Score a model on clips.

    Args:
        model: the model (built-in and taught gestures).
        clips: tracked clips.
        expected: motion kind -> the label that must fire first (kinds not listed: nothing
            may fire; random motions are always such kinds).

    Returns:
        {"frames", "detected", "gesture_clips", "correct", "by_kind": {kind: [correct, n]},
        "random_windows", "random_false_windows", "random_clips", "random_clips_fired",
        "fired": {kind: [first fired labels]}, "false_commands" (gestures fired in the clips of
        kinds that must not fire), "none_seconds" (their length)}.
    """
    res = {"frames": 0, "detected": 0, "gesture_clips": 0, "correct": 0, "by_kind": {},
           "random_windows": 0, "random_false_windows": 0, "random_clips": 0, "random_clips_fired": 0, "fired": {},
           "false_commands": 0, "none_seconds": 0.0}
    for clip in clips:
        res["frames"] += len(clip.times)
        res["detected"] += clip.detected
        fired, windows = replay(model, clip)
        res["fired"].setdefault(clip.kind, []).append(fired[0] if fired else NONE)
        if clip.kind in expected:
            ok = bool(fired) and fired[0] == expected[clip.kind]
            res["gesture_clips"] += 1
            res["correct"] += ok
            entry = res["by_kind"].setdefault(clip.kind, [0, 0])
            entry[0] += ok
            entry[1] += 1
        else:
            res["random_clips"] += 1
            res["random_clips_fired"] += bool(fired)
            res["false_commands"] += len(fired)
            res["none_seconds"] += clip.seconds
            res["random_windows"] += len(windows)
            res["random_false_windows"] += sum(w != NONE for w in windows)
    return res
