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

from rbd_local.gestures.motions import (  # noqa: F401 (the kinds are part of this module's API)
    GESTURE_KINDS,
    NONE_KINDS,
    RANDOM_KINDS,
    REAL_NONE_KINDS,
    ease,
    motion_path,
)

FOCAL_PX = 320.0 / np.tan(np.deg2rad(30.0))
HAND_LENGTH_M = 0.19
FRAME_SIZE = (640, 480)

#: Gesture kind -> the built-in gesture it must fire (a wrist wave is a wave).
EXPECTED = {"swipe_right": "swipe_right", "push_down": "push_down", "circle": "circle", "wave": "wave",
            "wrist_wave": "wave"}
#: Duration range of each gesture's motion [s] (default 0.6-1.0 s); people wave at 2-3 Hz.
MOTION_S = {"wave": (0.9, 1.15), "wrist_wave": (0.9, 1.3), "circle": (0.7, 1.1), "zigzag": (0.8, 1.1)}
#: Duration range of a motion in clips of the "real" style [s]: people swipe and push fast.
REAL_MOTION_S = {"swipe_right": (0.2, 0.45), "push_down": (0.25, 0.45), "swipe_left": (0.2, 0.45),
                 "swipe_up": (0.25, 0.45), "circle": (0.5, 0.9), "wave": (0.9, 1.15), "wrist_wave": (0.9, 1.3)}
#: Travel of swipes and pushes in clips of the "real" style [hand lengths] (issue 26: real swipes
#: travel 2.6-7 hand lengths; pushes down are shorter, the frame is lower than wide).
REAL_AMPLITUDE = {"swipe_right": (2.6, 7.0), "swipe_left": (2.6, 7.0), "swipe_up": (2.0, 4.0),
                  "push_down": (2.0, 4.0)}
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
        exposure_s: (low, high) exposure time [s]; each clip draws one; a hand that moves during
            the exposure is smeared along its path (motion blur); (0, 0): a sharp frame.
        second_hand: a second, still hand in the frame (resting at the side or near the face).
        arm: the arm is raised into the frame before the gesture and lowered out of it after.
        style: "photo" (the motions above) or "real" (issue 26: fast swipes and pushes of
            :data:`REAL_AMPLITUDE`, :data:`REAL_MOTION_S`).
        size: (width, height) of the delivered frames (rendered at 640 x 480, then scaled).
        backlight: a bright scene behind a dark hand (the camera exposes for the background).
    """

    def __init__(self, name: str, distance_m: tuple = (0.7, 1.3), hand: str = "both", fps: float = 30.0,
                 shake_px: float = 1.0, drop: float = 0.0, roll_deg: float = 25.0, brightness: float = 0.0,
                 contrast: float = 1.0, gamma: float = 1.0, noise: float = 2.0, in_range: bool = True,
                 exposure_s: tuple = (0.0, 0.0), second_hand: bool = False, arm: bool = False,
                 style: str = "photo", size: tuple = FRAME_SIZE, backlight: bool = False) -> None:
        """Store the condition (see the class attributes)."""
        if hand not in ("right", "left", "both"):
            raise ValueError("hand must be right, left or both")
        if style not in ("photo", "real"):
            raise ValueError("style must be photo or real")
        if not 0.0 <= exposure_s[0] <= exposure_s[1] or int(size[0]) < 32 or int(size[1]) < 32:
            raise ValueError("0 <= exposure low <= high and a frame of at least 32 x 32 required")
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
        self.exposure_s = (float(exposure_s[0]), float(exposure_s[1]))
        self.second_hand = bool(second_hand)
        self.arm = bool(arm)
        self.style = style
        self.size = (int(size[0]), int(size[1]))
        self.backlight = bool(backlight)

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


#: Distance range of the near hands that drift or close (issue 26: "a near hand") [m].
NEAR_M = (0.4, 0.8)
_REAL = {"exposure_s": (1.0 / 60.0, 1.0 / 30.0), "style": "real", "distance_m": (1.0, 1.6), "noise": 3.0}
_BUILT_IN_KINDS = ("swipe_right", "push_down", "circle", "wave")

#: The failure modes of real footage (issue 26), one table row each: (condition, gesture kinds
#: that must fire their gesture (:data:`EXPECTED`), motion kinds that must not fire). Every row
#: has the fast, long swipes and pushes of real people, and the motion blur of a 1/60-1/30 s
#: exposure, at 1-2 m.
FAILURE_MODES = (
    (Condition("1 fast motion, blur (exposure 1/60-1/30 s)", **_REAL), _BUILT_IN_KINDS, ("still", "wander")),
    (Condition("2 a second, still hand", second_hand=True, **_REAL), _BUILT_IN_KINDS, ("still", "wander")),
    (Condition("3 wrist waves; arm raised before, lowered after", arm=True, **_REAL),
     ("wrist_wave", "swipe_right", "push_down", "circle"), ("raise_lower", "swipe_left")),
    (Condition("4 near hands drifting or closing (0.4-0.8 m)", **_REAL), _BUILT_IN_KINDS, ("drift", "close")),
    (Condition("5 loose arm arcs", **_REAL), _BUILT_IN_KINDS, ("arm_arc",)),
    (Condition("6 low resolution 176 x 132, dim", size=(176, 132), gamma=2.0, contrast=0.6, **_REAL),
     _BUILT_IN_KINDS, ("still", "wander")),
    (Condition("7 backlit (bright scene, dark hand)", backlight=True, **_REAL), _BUILT_IN_KINDS, ("still", "wander")),
)


class _Light:
    """Brightness, contrast and gamma as a lookup table, plus sensor noise from a small bank."""

    def __init__(self, cond: Condition, rng: np.random.Generator) -> None:
        v = np.arange(256, dtype=np.float64) / 255.0
        self.lut = np.clip(255.0 * (cond.contrast * v**cond.gamma) + cond.brightness, 0, 255).astype(np.uint8)
        self.identity = bool(np.array_equal(self.lut, np.arange(256)))
        shape = (cond.size[1], cond.size[0], 3)
        self.noise = [rng.normal(0.0, cond.noise, shape).astype(np.int16) for _ in range(3)] if cond.noise > 0 else []

    def __call__(self, frame: np.ndarray, i: int) -> np.ndarray:
        import cv2

        out = frame if self.identity else cv2.LUT(frame, self.lut)
        if self.noise:
            out = np.clip(out.astype(np.int16) + self.noise[i % len(self.noise)], 0, 255).astype(np.uint8)
        return out


#: Durations of the motion of the no-command kinds of real people [s].
_NONE_MOTION_S = {"raise_lower": (0.3, 1.0), "drift": (1.5, 4.0), "close": (1.0, 2.0), "arm_arc": (0.8, 2.0)}


def _arm_segment(rng: np.random.Generator, fps: float, frm: np.ndarray, to: np.ndarray) -> np.ndarray:
    """Palm positions of an arm raised (or lowered) between two points in 0.4-0.7 s [px]."""
    n = max(3, int(round(rng.uniform(0.4, 0.7) * fps)))
    e = ease(np.linspace(0.0, 1.0, n))[:, None]
    return frm + (to - frm) * e


def _second_hand(sprites: list, sprite: object, left: bool, centres: np.ndarray, length: float,
                 rng: np.random.Generator, background: np.ndarray) -> np.ndarray:
    """The background with a second, still hand: resting at the side (fingers down) or near the face."""
    width, height = FRAME_SIZE
    other = sprites[(sprites.index(sprite) + 1) % len(sprites)]
    mid = float(np.median(centres[:, 0])) if len(centres) else width / 2
    side = -1.0 if mid > width / 2 else 1.0  # the free side of the frame
    x = width / 2 + side * rng.uniform(0.25, 0.4) * width
    if rng.random() < 0.5:  # resting at the side, fingers down
        centre = (x, height - rng.uniform(0.5, 0.9) * length)
        roll = 180.0 + rng.uniform(-25.0, 25.0)
    else:  # near the face (upper part of the frame), upright
        centre = (x, rng.uniform(0.3, 0.5) * height)
        roll = rng.uniform(-30.0, 30.0)
    return other.place(background, centre, length * rng.uniform(0.9, 1.1), roll, not left)


def make_clip(sprites: list, kind: str, cond: Condition, rng: np.random.Generator, motion_s: float = None,
              random_s: float = 4.0) -> tuple:
    """Render one clip.

    Gestures: 0.3-0.5 s still, the motion (:data:`MOTION_S`, or :data:`REAL_MOTION_S` in the
    "real" style, unless ``motion_s``), 0.9 s still. Random motions: ``random_s`` seconds of it.
    The no-command motions of real people (:data:`REAL_NONE_KINDS`) take their own time; a
    ``raise_lower`` clip, and every clip of a condition with ``arm``, starts with the arm being
    raised into the frame and ends with it lowered out of the frame.

    Args:
        sprites: hand sprites to choose from (one per real photo).
        kind: the motion.
        cond: the viewing condition.
        rng: random generator.
        motion_s: duration of the gesture's motion [s].
        random_s: length of a random-motion clip [s].

    Returns:
        (times (K,) [s], K BGR frames of ``cond.size``); lost frames are missing (their times skipped).
    """
    import cv2

    sprite = sprites[int(rng.integers(len(sprites)))]
    width, height = FRAME_SIZE
    real = cond.style == "real"
    near = real and kind in ("drift", "close")
    dist = rng.uniform(*(NEAR_M if near else cond.distance_m))
    length = hand_length_px(dist)
    left = cond.hand == "left" or (cond.hand == "both" and rng.random() < 0.5)
    roll0 = rng.uniform(-cond.roll_deg, cond.roll_deg)
    fps = cond.fps
    if kind in RANDOM_KINDS:
        n_before, n_move, n_after = 0, int(round(random_s * fps)), 0
    else:
        if kind in _NONE_MOTION_S:
            lo, hi = _NONE_MOTION_S[kind]
        elif real and kind in REAL_MOTION_S:
            lo, hi = REAL_MOTION_S[kind]
        else:
            lo, hi = MOTION_S.get(kind, (0.6, 1.0))
        dur = motion_s if motion_s is not None else rng.uniform(lo, hi)
        n_before = int(round(rng.uniform(0.3, 0.5) * fps))
        n_move = max(4, int(round(dur * fps)))
        n_after = int(round((rng.uniform(0.3, 0.6) if cond.arm or kind == "raise_lower" else 0.9) * fps))
    u = np.concatenate([np.zeros(n_before), np.linspace(0.0, 1.0, n_move), np.ones(n_after)])
    amplitude = REAL_AMPLITUDE.get(kind) if real else None
    if amplitude is not None:  # the whole travel stays in the frame (1.2 / 1.4 hand lengths spare)
        room = (width / length - 1.2) if kind in ("swipe_right", "swipe_left") else (height / length - 1.4)
        amplitude = (min(amplitude[0], room), min(amplitude[1], max(room, amplitude[0])))
    path, roll = motion_path(kind, rng, u, amplitude)
    squash = np.ones(len(u))
    if kind == "close":
        fist = rng.uniform(0.5, 0.65)
        shape = np.sin(np.pi * u) if rng.random() < 0.5 else ease(np.clip(2.0 * u, 0.0, 1.0))
        squash = 1.0 - (1.0 - fist) * shape
    tremor = np.cumsum(rng.normal(0.0, 0.002, path.shape), axis=0)
    xy = (path + tremor) * length
    # place the whole motion inside the frame (the hand reaches 0.6 lengths above the palm)
    lo = np.array([0.45, 0.7]) * length - xy.min(axis=0)
    hi = np.array([width, height]) - np.array([0.45, 0.3]) * length - xy.max(axis=0)
    start = np.where(hi > lo, rng.uniform(np.minimum(lo, hi), np.maximum(lo, hi)), (lo + hi) / 2)
    centres = start + xy
    if cond.arm or kind == "raise_lower":
        # the arm comes up from below the frame and goes down out of it (0.3 s without a hand after)
        below = np.array([rng.uniform(-0.5, 0.5) * length, height + 1.0 * length])
        up = _arm_segment(rng, fps, np.array([centres[0, 0], 0.0]) + below, centres[0])
        down = _arm_segment(rng, fps, centres[-1], np.array([centres[-1, 0], 0.0]) + below)
        out = np.repeat(down[-1:], int(round(0.3 * fps)), axis=0)
        tilt = rng.uniform(-30.0, 30.0)
        roll = np.concatenate([tilt * (1.0 - ease(np.linspace(0, 1, len(up)))), roll,
                               tilt * ease(np.linspace(0, 1, len(down))), np.full(len(out), tilt)])
        squash = np.concatenate([np.ones(len(up)), squash, np.ones(len(down) + len(out))])
        centres = np.concatenate([up, centres, down, out])
    shake = rng.normal(0.0, cond.shake_px * length / hand_length_px(1.0), centres.shape)
    centres = centres + shake
    background = sprite.plain_background(FRAME_SIZE)
    gain = 1.0
    if cond.backlight:
        # a bright window behind the visitor; the camera exposes for it, so the hand is dark
        ramp = np.linspace(1.0, 0.85, height, dtype=np.float32)[:, None, None]
        background = np.clip(rng.uniform(225.0, 250.0) * ramp * np.ones((1, width, 3), np.float32), 0,
                             255).astype(np.uint8)
        gain = rng.uniform(0.3, 0.45)
    if cond.second_hand:
        background = _second_hand(sprites, sprite, left, centres, length, rng, background)
    exposure = rng.uniform(*cond.exposure_s)
    light = _Light(cond, rng)
    idx = np.arange(len(centres), dtype=np.float64)
    times, frames = [], []
    for i in range(len(centres)):
        if cond.drop and rng.random() < cond.drop:
            continue
        # motion blur: the frame is the mean of the hand's images over the exposure
        t0 = max(0.0, i - exposure * fps)
        sub = np.array([float(i)])
        if exposure > 0 and i > 0:
            moved = np.linalg.norm(centres[i] - np.array([np.interp(t0, idx, centres[:, k]) for k in range(2)]))
            moved += abs(np.deg2rad(roll0 + roll[i]) - np.deg2rad(roll0 + np.interp(t0, idx, roll))) * length
            k = int(np.clip(np.ceil(moved / 2.0), 1, 24))
            sub = np.linspace(t0, float(i), k) if k > 1 else sub
        acc = None
        for ts in sub:
            c = (np.interp(ts, idx, centres[:, 0]), np.interp(ts, idx, centres[:, 1]))
            img = sprite.place(background, c, length, roll0 + np.interp(ts, idx, roll), left,
                               squash=float(np.interp(ts, idx, squash)), gain=gain)
            acc = img.astype(np.float32) if acc is None else acc + img
        frame = np.clip(acc / len(sub) + 0.5, 0, 255).astype(np.uint8) if len(sub) > 1 else img
        if cond.size != FRAME_SIZE:
            frame = cv2.resize(frame, cond.size, interpolation=cv2.INTER_AREA)
        frames.append(light(frame, i))
        times.append(i / fps)
    return np.array(times), frames


def gesture_kinds(cond: Condition) -> tuple:
    """The built-in gesture kinds of a row: the failure-mode row's own, else the four gestures."""
    for row, kinds, _none in FAILURE_MODES:
        if row is cond:
            return kinds
    return BUILT_IN


def track_clip(detector: object, frames: list) -> np.ndarray:
    """Key points of every frame of one clip, the detector's tracking reset first.

    Args:
        detector: a :class:`~rbd_local.gestures.detector.HandDetector` (video mode).
        frames: the clip's BGR frames.

    Returns:
        (K, H, 21, 3) key points in pixels of up to H = ``detector.max_hands`` hands per frame
        (in the detector's order), NaN where no hand was found.
    """
    blank = np.zeros_like(frames[0]) if len(frames) else np.zeros((FRAME_SIZE[1], FRAME_SIZE[0], 3), np.uint8)
    detector.detect_hands(blank)  # loses the previous clip's hand: the next frame is detected afresh
    out = np.full((len(frames), getattr(detector, "max_hands", 1), 21, 3), np.nan)
    for i, frame in enumerate(frames):
        for j, (pts, _score) in enumerate(detector.detect_hands(frame)[:out.shape[1]]):
            out[i, j] = pts
    return out
