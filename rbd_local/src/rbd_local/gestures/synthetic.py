"""Synthetic hand key-point sequences for tests, benchmarks and the bootstrap model.

Every sequence is one classifier window: ``samples`` frames of 21 key points in pixels of a
640 x 480 image (x right, y down, z relative depth). A sequence is built from a hand template
(:mod:`rbd_local.gestures.hand`) that is scaled, rotated, mirrored, curled, moved along a
trajectory and disturbed with per-frame jitter like MediaPipe's.

The four gestures (one per trick) are motions, not poses, so any hand posture works:

- ``swipe_right``: the hand sweeps to the right (image x grows),
- ``circle``: the hand draws a circle (either direction),
- ``wave``: the hand waves side to side 1.5 to 3.5 times,
- ``push_down``: the hand moves down.

The ``none`` class covers what must not trigger: a still hand, random wandering, random
oscillations and unknown gestures (swipe left or up, diagonal swipes, a vertical wave,
pushing towards the camera, opening and closing the fist).
"""

import numpy as np

from rbd_local.gestures.hand import NUM_LANDMARKS, hand_shape

GESTURES = ("swipe_right", "circle", "wave", "push_down")
NONE = "none"
CLASSES = GESTURES + (NONE,)
RANDOM_KINDS = ("static", "random_walk", "random_points")
UNKNOWN_KINDS = ("swipe_left", "swipe_up", "diagonal", "vertical_wave", "push_towards", "fist_pump")
#: Motions of real people that are no command (issue 26): loose arm arcs, slow drift, a hand closing.
REAL_KINDS = ("arm_arc", "drift", "close")
NONE_KINDS = RANDOM_KINDS + UNKNOWN_KINDS + REAL_KINDS
DEFAULT_SAMPLES = 24
#: Share of the window a motion takes (uniform in this range).
ACTIVITY = (0.35, 1.0)
#: Largest camera shake: standard deviation of a shift of the whole hand per frame [hand sizes].
SHAKE = 0.1
#: Share of the window a fast swipe or push may take at least (real people swipe in 0.3 s).
FAST_ACTIVITY = 0.2
#: Probability that a window has the hand lost for 0.15-0.5 s, bridged by straight lines as the
#: recognizer bridges it (:mod:`.tracks`): fast real motions blur and MediaPipe loses them.
GAP_PROB = 0.25
IMAGE_SIZE = (640, 480)


def _ease(tau: np.ndarray) -> np.ndarray:
    return tau * tau * (3.0 - 2.0 * tau)


def _activity(rng: np.random.Generator, t: np.ndarray, low: float = ACTIVITY[0]) -> np.ndarray:
    """Gesture progress in [0, 1]: the gesture fills ``low``-1 (:data:`ACTIVITY`) of the window."""
    frac = rng.uniform(low, ACTIVITY[1])
    start = rng.uniform(0.0, 1.0 - frac)
    return np.clip((t - start) / frac, 0.0, 1.0)


def _smooth_noise(rng: np.random.Generator, n: int, width: float) -> np.ndarray:
    """Smoothed random walk with unit peak-to-peak size."""
    steps = rng.normal(size=(n + 8, 2))
    walk = np.cumsum(steps, axis=0)
    kernel = np.ones(max(1, int(width)))
    kernel /= kernel.sum()
    sm = np.stack([np.convolve(walk[:, i], kernel, mode="same") for i in range(2)], axis=1)[4 : n + 4]
    sm -= sm[0]
    span = np.ptp(sm, axis=0).max()
    return sm / span if span > 1e-9 else sm


def _trajectory(
    kind: str, rng: np.random.Generator, t: np.ndarray, curl0: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hand-centre path (hand units), scale factor, curl and turn about the wrist [rad] per frame."""
    n = len(t)
    path = np.zeros((n, 2))
    scale = np.ones(n)
    spin = np.zeros(n)
    curl = np.tile(curl0, (n, 1))
    fast = kind in ("swipe_right", "swipe_left", "swipe_up", "diagonal", "push_down")
    tau = _activity(rng, t, FAST_ACTIVITY if fast else ACTIVITY[0])
    if kind == "swipe_right" or kind in ("swipe_left", "swipe_up", "diagonal", "push_down"):
        # 1-5 hand lengths (a hand length is about two of these units)
        amp = rng.uniform(2.0, 10.0) if kind != "push_down" else rng.uniform(1.6, 7.0)
        base = {"swipe_right": 0.0, "push_down": np.pi / 2, "swipe_left": np.pi, "swipe_up": -np.pi / 2}
        if kind == "diagonal":
            angle = rng.choice([-np.pi / 4, -3 * np.pi / 4, 3 * np.pi / 4]) + rng.uniform(-0.2, 0.2)
        else:
            angle = base[kind] + rng.uniform(-0.35, 0.35)
        e = _ease(tau)
        path = amp * e[:, None] * np.array([np.cos(angle), np.sin(angle)])
        path[:, 1] += rng.uniform(-0.4, 0.4) * np.sin(np.pi * tau)  # a little arc
    elif kind == "circle":
        radius = rng.uniform(0.8, 2.0)
        ratio = rng.uniform(0.7, 1.3)
        turns = rng.uniform(0.85, 1.3) * rng.choice([-1.0, 1.0])
        phi0 = rng.uniform(0, 2 * np.pi)
        phi = phi0 + 2 * np.pi * turns * tau
        path = radius * np.stack([np.cos(phi) - np.cos(phi0), ratio * (np.sin(phi) - np.sin(phi0))], axis=1)
    elif kind == "wave" and rng.random() < 0.5:
        # a wave from the wrist: the hand turns back and forth about the wrist, the palm barely moves
        cycles = rng.uniform(1.5, 3.5)
        s = np.sin(2 * np.pi * cycles * tau + rng.uniform(-0.3, 0.3))
        spin = np.deg2rad(rng.uniform(18.0, 45.0)) * s
        path = rng.uniform(0.0, 0.3) * s[:, None] * np.array([1.0, 0.0])
    elif kind in ("wave", "vertical_wave"):
        amp = rng.uniform(0.5, 1.5)
        cycles = rng.uniform(1.5, 3.5)
        s = amp * np.sin(2 * np.pi * cycles * tau + rng.uniform(-0.3, 0.3))
        tilt = rng.uniform(-0.25, 0.25) + (np.pi / 2 if kind == "vertical_wave" else 0.0)
        path = s[:, None] * np.array([np.cos(tilt), np.sin(tilt)])
    elif kind == "arm_arc":
        # loose arm movement: an arc of 50-120 degrees about an elbow or shoulder 5-9 units away
        radius = rng.uniform(5.0, 9.0)
        sweep = np.deg2rad(rng.uniform(50.0, 120.0)) * rng.choice([-1.0, 1.0])
        prog = np.sin(np.pi * tau) if rng.random() < 0.5 else _ease(tau)
        base = np.deg2rad(rng.uniform(-60.0, 60.0)) - sweep / 2
        ang = base + sweep * prog
        path = radius * np.stack([np.sin(ang) - np.sin(base), -(np.cos(ang) - np.cos(base))], axis=1)
        spin = ang - base
    elif kind == "drift":
        # a slow, steady drift (0.3-1.8 units in the window) in any direction
        angle = rng.uniform(0.0, 2 * np.pi)
        path = rng.uniform(0.3, 1.8) * t[:, None] * np.array([np.cos(angle), np.sin(angle)])
        path += rng.uniform(0.0, 0.3) * _smooth_noise(rng, n, 6)
    elif kind == "close":
        # the hand closes into a fist (maybe opening again) while drifting a little
        closed = np.sin(np.pi * tau) if rng.random() < 0.5 else _ease(tau)
        curl = np.clip(curl + closed[:, None] * rng.uniform(0.6, 1.0), 0, 1)
        scale = 1.0 - rng.uniform(0.0, 0.25) * closed
        angle = rng.uniform(0.0, 2 * np.pi)
        path = rng.uniform(0.0, 1.0) * closed[:, None] * np.array([np.cos(angle), np.sin(angle)])
    elif kind == "static":
        path = rng.uniform(0.0, 0.3) * _smooth_noise(rng, n, 6)
    elif kind == "random_walk":
        path = rng.uniform(0.3, 3.0) * _smooth_noise(rng, n, rng.integers(2, 8))
    elif kind == "random_points":
        # Aimless moves between random points anywhere around the hand.
        k = int(rng.integers(3, 7))
        knots_t = np.sort(np.concatenate([[0.0, 1.0], rng.uniform(0, 1, k - 2)]))
        knots = rng.uniform(-1.0, 1.0, (k, 2)) * rng.uniform(0.3, 2.0)
        path = np.stack([np.interp(t, knots_t, knots[:, i]) for i in range(2)], axis=1)
        kernel = np.ones(3) / 3.0
        path = np.stack([np.convolve(np.pad(path[:, i], 1, mode="edge"), kernel, "valid") for i in range(2)], 1)
        path -= path[0]
    elif kind == "push_towards":
        scale = 1.0 + rng.uniform(0.3, 1.0) * _ease(tau)
        path = rng.uniform(0.0, 0.4) * _smooth_noise(rng, n, 6)
    elif kind == "fist_pump":
        cycles = rng.uniform(1.0, 2.5)
        closed = 0.5 - 0.5 * np.cos(2 * np.pi * cycles * tau)
        curl = np.clip(curl + closed[:, None] * rng.uniform(0.6, 1.0), 0, 1)
        path = rng.uniform(0.0, 0.4) * _smooth_noise(rng, n, 6)
    else:
        raise ValueError("unknown synthetic motion %r" % kind)
    return path, scale, curl, spin


def _random_curl(rng: np.random.Generator) -> np.ndarray:
    posture = rng.integers(0, 4)
    if posture == 0:  # open palm
        return rng.uniform(0.0, 0.2, 5)
    if posture == 1:  # pointing index finger
        c = rng.uniform(0.7, 1.0, 5)
        c[1] = rng.uniform(0.0, 0.15)
        return c
    if posture == 2:  # fist
        return rng.uniform(0.75, 1.0, 5)
    return rng.uniform(0.0, 1.0, 5)  # relaxed, anything


def random_hand(rng: np.random.Generator) -> dict:
    """Draw a hand: size [px], orientation [rad], handedness, finger curl, depth profile, jitter."""
    return {
        "size": rng.uniform(0.06, 0.2) * IMAGE_SIZE[1],  # wrist to middle-finger base [px]
        "angle": rng.uniform(-1.9, 1.9),
        "mirror": -1.0 if rng.random() < 0.5 else 1.0,
        "curl": _random_curl(rng),
        "depth": rng.normal(0.0, 0.1, NUM_LANDMARKS),
        "jitter": rng.uniform(0.01, 0.05),
        "shake": rng.uniform(0.0, SHAKE),
    }


def generate(
    kind: str, rng: np.random.Generator, samples: int = DEFAULT_SAMPLES, hand: dict = None, start: np.ndarray = None,
    gaps: bool = True,
) -> np.ndarray:
    """Generate one window of key points.

    Args:
        kind: a gesture name from :data:`GESTURES` or a none-class kind from :data:`NONE_KINDS`.
        rng: random generator (seed it for reproducible data).
        samples: frames per window.
        hand: the hand to move (:func:`random_hand`); default a new random one.
        start: (2,) starting position of the hand [px]; default a random one that keeps the
            whole motion inside the image.
        gaps: lose the hand for a while in some windows (:data:`GAP_PROB`, :func:`bridge_gap`).

    Returns:
        (samples, 21, 3) float array in pixels of a 640 x 480 image.

    Raises:
        ValueError: for an unknown kind or fewer than 4 samples.
    """
    if samples < 4:
        raise ValueError("a window needs at least 4 samples, got %d" % samples)
    hand = random_hand(rng) if hand is None else hand
    t = np.linspace(0.0, 1.0, samples)
    path, scale, curl, spin = _trajectory(kind, rng, t, hand["curl"])
    width, height = IMAGE_SIZE
    size, angle, mirror, depth, jitter = hand["size"], hand["angle"], hand["mirror"], hand["depth"], hand["jitter"]
    wobble = rng.uniform(0.0, 0.25) * _smooth_noise(rng, samples, 6)[:, 0]
    if start is None:
        # Keep the whole motion inside the image.
        span = (path.max(axis=0) - path.min(axis=0)) * size
        lo = np.array([2.5 * size, 2.5 * size]) - path.min(axis=0) * size
        hi = np.array([width, height]) - 2.5 * size - path.max(axis=0) * size
        start = np.where(hi > lo, rng.uniform(np.minimum(lo, hi), np.maximum(lo, hi)),
                         (np.array([width, height]) - span) / 2)
    shapes = hand_shape(curl) * np.array([mirror, 1.0])  # (samples, 21, 2)
    c, s = np.cos(angle + wobble + spin), np.sin(angle + wobble + spin)
    rot = np.stack([np.stack([c, -s], axis=1), np.stack([s, c], axis=1)], axis=1)  # (samples, 2, 2)
    pts = np.einsum("nij,nkj->nki", rot, shapes) * (size * scale)[:, None, None]
    pts += np.asarray(start) + path[:, None, :] * size
    pts += rng.normal(0.0, jitter * size, pts.shape)
    pts += rng.normal(0.0, hand.get("shake", 0.0) * size, (samples, 1, 2))  # the camera shakes
    out = np.empty((samples, NUM_LANDMARKS, 3))
    out[:, :, :2] = pts
    out[:, :, 2] = depth * size * scale[:, None] + rng.normal(0.0, jitter * size, (samples, NUM_LANDMARKS))
    if gaps and rng.random() < GAP_PROB:
        bridge_gap(out, rng)
    return out


def bridge_gap(window: np.ndarray, rng: np.random.Generator) -> None:
    """Lose the hand for 0.15-0.5 of a 1.2 s window in its middle and bridge it by straight lines (in place)."""
    n = len(window)
    length = int(round(rng.uniform(0.125, 0.42) * n))
    if length < 1 or n - length < 4:
        return
    start = int(rng.integers(1, n - length))
    a, b = window[start - 1], window[start + length]
    for k in range(length):
        w = (k + 1.0) / (length + 1.0)
        window[start + k] = a * (1.0 - w) + b * w


def stream(kinds: list, seed: int, fps: float = 30.0, window_s: float = 1.2) -> list:
    """One continuous hand performing ``kinds`` one after another (each ``window_s`` long).

    Returns:
        List of (time [s], (21, 3) key points) at ``fps``.
    """
    rng = np.random.default_rng(seed)
    hand = random_hand(rng)
    hand["size"] = IMAGE_SIZE[1] * 0.1
    n = int(round(window_s * fps))
    pos = np.array(IMAGE_SIZE, dtype=np.float64) / 2 - np.array([0.15 * IMAGE_SIZE[0], 0.0])
    frames = []
    for kind in kinds:
        w = generate(kind, rng, n, hand=hand, start=pos, gaps=False)
        pos = w[-1, :, :2].mean(axis=0) - (w[0, :, :2].mean(axis=0) - pos)
        frames.extend(w)
    return [(i / fps, f) for i, f in enumerate(frames)]


def label_of(kind: str) -> str:
    """Class label of a motion kind: the gesture itself or ``none``."""
    return kind if kind in GESTURES else NONE


def dataset(
    seed: int, per_gesture: int, per_none_kind: int, samples: int = DEFAULT_SAMPLES, kinds: tuple = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Generate a labelled set of windows.

    Args:
        seed: random seed; the same seed gives the same data.
        per_gesture: windows per gesture class.
        per_none_kind: windows per none-class kind.
        samples: frames per window.
        kinds: none-class kinds to include (default: all of :data:`NONE_KINDS`).

    Returns:
        (windows (N, samples, 21, 3), labels (N,) str, kinds (N,) str).
    """
    rng = np.random.default_rng(seed)
    kinds_list = [g for g in GESTURES for _ in range(per_gesture)]
    kinds_list += [k for k in (kinds if kinds is not None else NONE_KINDS) for _ in range(per_none_kind)]
    windows = np.stack([generate(k, rng, samples) for k in kinds_list]) if kinds_list else np.empty((0, samples, 21, 3))
    kinds_arr = np.array(kinds_list, dtype=str)
    labels = np.array([label_of(k) for k in kinds_list], dtype=str)
    return windows, labels, kinds_arr
