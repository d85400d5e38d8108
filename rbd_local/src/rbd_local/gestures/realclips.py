"""Evaluation clips made from real hand photos: gestures, random motion, and viewing conditions.

A clip is a sequence of camera frames in which the real hand of a photo (cut out by
:class:`~rbd_local.gestures.photo_clip.HandSprite`) performs one motion: held still, moved
along the gesture's path, held still again. The path is given in *hand lengths* (wrist to the
longest fingertip) of the image plane, so the same gesture looks the same at every distance.
A :class:`Condition` sets how the camera sees it: distance (hand size in pixels), left or
right hand, frame rate, camera shake, dropped frames, and light (brightness, contrast, gamma,
sensor noise).

Camera model: 640 x 480 pixels, 60 degrees horizontal field of view (a typical laptop
webcam; focal length 554 px), adult hand 0.19 m long, so the hand is 105 px long at 1 m,
210 px at 0.5 m and 35 px at 3 m.

The photos are real, their motion is not: a photo does not bend its fingers or turn its palm,
and the paths are drawn from the ranges below, not recorded from people.
"""

import numpy as np

FOCAL_PX = 320.0 / np.tan(np.deg2rad(30.0))
HAND_LENGTH_M = 0.19
FRAME_SIZE = (640, 480)

#: Gestures a clip can show (the four built-in ones and some a visitor might teach).
GESTURE_KINDS = ("swipe_right", "push_down", "circle", "wave", "swipe_up", "swipe_left", "checkmark", "zigzag")
#: Motions that must not trigger anything.
RANDOM_KINDS = ("still", "wander", "random_points")
#: Duration range of each gesture's motion [s] (default 0.6-1.0 s); people wave at 2-3 Hz.
MOTION_S = {"wave": (0.9, 1.15), "circle": (0.7, 1.1), "zigzag": (0.8, 1.1)}
#: Built-in gesture classes and the trick each one triggers (the shipped configuration).
BUILT_IN = ("swipe_right", "circle", "wave", "push_down")


def hand_length_px(distance_m: float) -> float:
    """Hand length in pixels at ``distance_m`` from the camera model's camera."""
    if not distance_m > 0:
        raise ValueError("distance must be > 0")
    return FOCAL_PX * HAND_LENGTH_M / float(distance_m)


class Condition:
    """How the camera sees a clip.

    Attributes:
        name: row label of the evaluation table.
        distance_m: (low, high) camera distance range [m]; each clip draws one value.
        hand: "right", "left" or "both" (each clip draws one).
        fps: frame rate [1/s].
        shake_px: camera shake, standard deviation of a per-frame shift at 1 m [px]
            (scaled with the hand's size).
        drop: probability that a frame is lost.
        roll_deg: largest hand roll away from upright [deg].
        brightness, contrast, gamma: light; a pixel v in [0, 1] becomes
            ``contrast * v ** gamma + brightness / 255``.
        noise: sensor noise standard deviation [grey levels].
        in_range: whether the goals apply to this condition (see README).
    """

    def __init__(self, name: str, distance_m: tuple = (0.7, 1.3), hand: str = "both", fps: float = 30.0,
                 shake_px: float = 1.0, drop: float = 0.0, roll_deg: float = 25.0, brightness: float = 0.0,
                 contrast: float = 1.0, gamma: float = 1.0, noise: float = 2.0, in_range: bool = True) -> None:
        """Store the condition (see the class attributes)."""
        if hand not in ("right", "left", "both"):
            raise ValueError("hand must be right, left or both")
        if not fps > 0 or not 0.0 <= drop < 1.0 or not contrast > 0 or not gamma > 0:
            raise ValueError("fps > 0, 0 <= drop < 1, contrast > 0 and gamma > 0 required")
        self.name = name
        self.distance_m = (float(distance_m[0]), float(distance_m[1]))
        self.hand = hand
        self.fps = float(fps)
        self.shake_px = float(shake_px)
        self.drop = float(drop)
        self.roll_deg = float(roll_deg)
        self.brightness = float(brightness)
        self.contrast = float(contrast)
        self.gamma = float(gamma)
        self.noise = float(noise)
        self.in_range = bool(in_range)

    def __repr__(self) -> str:
        """Readable form for logs."""
        return "Condition(%r)" % self.name


BASELINE = Condition("baseline: 0.7-1.3 m, both hands, 30 fps")

#: The rows of the robustness table.
CONDITIONS = (
    BASELINE,
    Condition("distance 0.5 m", distance_m=(0.5, 0.5)),
    Condition("distance 1.0 m", distance_m=(1.0, 1.0)),
    Condition("distance 1.5 m", distance_m=(1.5, 1.5)),
    Condition("distance 2.0 m", distance_m=(2.0, 2.0), in_range=False),
    Condition("distance 3.0 m", distance_m=(3.0, 3.0), in_range=False),
    Condition("right hand only", hand="right"),
    Condition("left hand only", hand="left"),
    Condition("15 fps", fps=15.0),
    Condition("camera shake (4 px)", shake_px=4.0),
    Condition("20 % frames dropped", drop=0.2),
    Condition("hand rolled up to 60 deg", roll_deg=60.0),
    Condition("bright (+60, contrast 1.2)", brightness=60.0, contrast=1.2),
    Condition("low contrast (0.4)", contrast=0.4, brightness=70.0),
    Condition("dim (gamma 2, contrast 0.6)", gamma=2.0, contrast=0.6, noise=3.0),
    Condition("dark (gamma 3, contrast 0.35)", gamma=3.0, contrast=0.35, noise=4.0),
    Condition("very dark (gamma 3, contrast 0.2)", gamma=3.0, contrast=0.2, noise=5.0),
)


def _ease(u: np.ndarray) -> np.ndarray:
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def _polyline(points: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Position along a polyline at progress u in [0, 1], each segment eased."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg)]) / max(seg.sum(), 1e-9)
    out = np.empty((len(u), 2))
    for i, x in enumerate(u):
        k = min(int(np.searchsorted(cum, x, side="right")) - 1, len(seg) - 1)
        k = max(k, 0)
        local = (x - cum[k]) / max(cum[k + 1] - cum[k], 1e-9)
        out[i] = points[k] + (points[k + 1] - points[k]) * _ease(np.array([local]))[0]
    return out


def motion_path(kind: str, rng: np.random.Generator, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The palm's path of one performance.

    Args:
        kind: one of :data:`GESTURE_KINDS` or :data:`RANDOM_KINDS`.
        rng: random generator (amplitudes, directions, speeds vary per performance).
        u: (N,) progress of the motion in [0, 1].

    Returns:
        ((N, 2) palm position relative to the start [hand lengths], x right, y down;
        (N,) extra hand roll [deg]).

    Raises:
        ValueError: for an unknown kind.
    """
    n = len(u)
    roll = np.zeros(n)
    tilt = np.deg2rad(rng.uniform(-12.0, 12.0))
    rot = np.array([[np.cos(tilt), -np.sin(tilt)], [np.sin(tilt), np.cos(tilt)]])
    e = _ease(u)
    if kind in ("swipe_right", "swipe_left", "swipe_up", "push_down"):
        amp = rng.uniform(1.1, 2.0) if kind != "push_down" else rng.uniform(0.9, 1.6)
        direction = {"swipe_right": (1.0, 0.0), "swipe_left": (-1.0, 0.0), "swipe_up": (0.0, -1.0),
                     "push_down": (0.0, 1.0)}[kind]
        path = amp * e[:, None] * np.array(direction)
        side = np.array([-direction[1], direction[0]])
        path += rng.uniform(-0.15, 0.15) * np.sin(np.pi * u)[:, None] * side  # a slight arc
    elif kind == "circle":
        radius = rng.uniform(0.45, 0.8)
        ratio = rng.uniform(0.8, 1.2)
        turns = rng.uniform(0.95, 1.2) * rng.choice([-1.0, 1.0])
        phi0 = rng.uniform(0, 2 * np.pi)
        phi = phi0 + 2 * np.pi * turns * e
        path = radius * np.stack([np.cos(phi) - np.cos(phi0), ratio * (np.sin(phi) - np.sin(phi0))], axis=1)
    elif kind == "wave":
        amp = rng.uniform(0.25, 0.5)
        cycles = rng.uniform(2.0, 3.0)  # over 0.9-1.15 s: 1.7-3.3 Hz
        s = np.sin(2 * np.pi * cycles * u) * np.sin(np.pi * u) ** 0.3
        path = amp * np.stack([s, 0.05 * np.abs(s)], axis=1)
        roll = -20.0 * s  # the wrist pivots with the wave
    elif kind == "checkmark":
        a = rng.uniform(0.8, 1.2)
        pts = np.array([[0.0, 0.0], [0.45, 0.6], [1.3, -0.9]]) * a
        path = _polyline(pts, u)
    elif kind == "zigzag":
        a = rng.uniform(0.8, 1.2)
        pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 0.7], [1.0, 0.7]]) * a
        path = _polyline(pts, u)
    elif kind == "still":
        path = np.cumsum(rng.normal(0.0, 0.004, (n, 2)), axis=0)
    elif kind == "wander":
        k = max(3, n // 12)
        knots = np.cumsum(rng.normal(0.0, rng.uniform(0.1, 0.35), (k, 2)), axis=0)
        ku = np.linspace(0.0, 1.0, k)
        path = np.stack([np.interp(u, ku, knots[:, i]) for i in range(2)], axis=1)
        path -= path[0]
    elif kind == "random_points":
        k = int(rng.integers(3, 7))
        knots = rng.uniform(-1.0, 1.0, (k, 2)) * rng.uniform(0.2, 1.0)
        knots[0] = 0.0
        path = _polyline(knots, u)
    else:
        raise ValueError("unknown motion %r" % kind)
    if kind not in RANDOM_KINDS:
        path = path @ rot.T
    return path, roll


class _Light:
    """Brightness, contrast and gamma as a lookup table, plus sensor noise from a small bank."""

    def __init__(self, cond: Condition, rng: np.random.Generator) -> None:
        v = np.arange(256, dtype=np.float64) / 255.0
        self.lut = np.clip(255.0 * (cond.contrast * v**cond.gamma) + cond.brightness, 0, 255).astype(np.uint8)
        self.identity = bool(np.array_equal(self.lut, np.arange(256)))
        shape = (FRAME_SIZE[1], FRAME_SIZE[0], 3)
        self.noise = [rng.normal(0.0, cond.noise, shape).astype(np.int16) for _ in range(3)] if cond.noise > 0 else []

    def __call__(self, frame: np.ndarray, i: int) -> np.ndarray:
        import cv2

        out = frame if self.identity else cv2.LUT(frame, self.lut)
        if self.noise:
            out = np.clip(out.astype(np.int16) + self.noise[i % len(self.noise)], 0, 255).astype(np.uint8)
        return out


def make_clip(sprites: list, kind: str, cond: Condition, rng: np.random.Generator, motion_s: float = None,
              random_s: float = 4.0) -> tuple[np.ndarray, list]:
    """Render one clip.

    Gestures: 0.3-0.5 s still, the motion (:data:`MOTION_S`, unless ``motion_s``), 0.9 s still.
    Random motions: ``random_s`` seconds of it.

    Args:
        sprites: hand sprites to choose from (one per real photo).
        kind: the motion.
        cond: the viewing condition.
        rng: random generator.
        motion_s: duration of the gesture's motion [s].
        random_s: length of a random-motion clip [s].

    Returns:
        (times (K,) [s], K BGR frames); lost frames are missing (their times skipped).
    """
    sprite = sprites[int(rng.integers(len(sprites)))]
    width, height = FRAME_SIZE
    dist = rng.uniform(*cond.distance_m)
    length = hand_length_px(dist)
    left = cond.hand == "left" or (cond.hand == "both" and rng.random() < 0.5)
    roll0 = rng.uniform(-cond.roll_deg, cond.roll_deg)
    fps = cond.fps
    if kind in RANDOM_KINDS:
        n_before, n_move, n_after = 0, int(round(random_s * fps)), 0
    else:
        lo, hi = MOTION_S.get(kind, (0.6, 1.0))
        dur = motion_s if motion_s is not None else rng.uniform(lo, hi)
        n_before = int(round(rng.uniform(0.3, 0.5) * fps))
        n_move = max(4, int(round(dur * fps)))
        n_after = int(round(0.9 * fps))
    u = np.concatenate([np.zeros(n_before), np.linspace(0.0, 1.0, n_move), np.ones(n_after)])
    path, roll = motion_path(kind, rng, u)
    tremor = np.cumsum(rng.normal(0.0, 0.002, path.shape), axis=0)
    xy = (path + tremor) * length
    # place the whole motion inside the frame (the hand reaches 0.6 lengths above the palm)
    lo = np.array([0.45, 0.7]) * length - xy.min(axis=0)
    hi = np.array([width, height]) - np.array([0.45, 0.3]) * length - xy.max(axis=0)
    start = np.where(hi > lo, rng.uniform(np.minimum(lo, hi), np.maximum(lo, hi)), (lo + hi) / 2)
    shake = rng.normal(0.0, cond.shake_px * length / hand_length_px(1.0), xy.shape)
    centres = start + xy + shake
    background = sprite.plain_background(FRAME_SIZE)
    light = _Light(cond, rng)
    times, frames = [], []
    for i in range(len(u)):
        if cond.drop and rng.random() < cond.drop:
            continue
        frame = sprite.place(background, centres[i], length, roll0 + roll[i], left)
        frames.append(light(frame, i))
        times.append(i / fps)
    return np.array(times), frames


def track_clip(detector: object, frames: list) -> np.ndarray:
    """Key points of every frame of one clip, the detector's tracking reset first.

    Args:
        detector: a :class:`~rbd_local.gestures.detector.HandDetector` (video mode).
        frames: the clip's BGR frames.

    Returns:
        (K, 21, 3) key points in pixels, NaN where no hand was found.
    """
    blank = np.zeros((FRAME_SIZE[1], FRAME_SIZE[0], 3), np.uint8)
    detector.detect(blank)  # loses the previous clip's hand: the next frame is detected afresh
    out = np.full((len(frames), 21, 3), np.nan)
    for i, frame in enumerate(frames):
        found = detector.detect(frame)
        if found is not None:
            out[i] = found[0]
    return out
