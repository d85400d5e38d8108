"""The palm's path of each motion kind in the real-photo clips (:mod:`.realclips`).

A path is given in *hand lengths* of the image plane relative to where the motion starts (x
right, y down), with the hand's roll [deg] along it: the gestures (swipes, push, circle, palm and
wrist waves, the taught kinds), the random motions that must not fire, and the motions of real
people that are no command (issue 26: an arm raised and lowered, a drifting or closing hand,
loose arm arcs). The ranges are drawn per performance from ``rng``; they are not recordings.
"""

import numpy as np

#: Gestures a clip can show (the four built-in ones and some a visitor might teach).
GESTURE_KINDS = ("swipe_right", "push_down", "circle", "wave", "swipe_up", "swipe_left", "checkmark", "zigzag")
#: Motions that must not trigger anything.
RANDOM_KINDS = ("still", "wander", "random_points")
#: Motions of real people that are no command (issue 26): an arm raised and lowered again, a hand
#: drifting slowly, a hand closing into a fist (and opening), loose arm movement along arcs.
REAL_NONE_KINDS = ("raise_lower", "drift", "close", "arm_arc")
#: Every motion kind that must not fire.
NONE_KINDS = RANDOM_KINDS + REAL_NONE_KINDS


def ease(u: np.ndarray) -> np.ndarray:
    """Smoothstep of ``u`` clipped to [0, 1]: starts and ends at rest."""
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
        out[i] = points[k] + (points[k + 1] - points[k]) * ease(np.array([local]))[0]
    return out


def motion_path(kind: str, rng: np.random.Generator, u: np.ndarray, amplitude: tuple = None) -> tuple:
    """The palm's path of one performance.

    Args:
        kind: one of :data:`GESTURE_KINDS`, ``wrist_wave``, or of :data:`NONE_KINDS`.
        rng: random generator (amplitudes, directions, speeds vary per performance).
        u: (N,) progress of the motion in [0, 1].
        amplitude: (low, high) travel of a swipe or push [hand lengths] instead of the default.

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
    e = ease(u)
    if kind in ("swipe_right", "swipe_left", "swipe_up", "push_down"):
        if amplitude is not None:
            amp = rng.uniform(*amplitude)
        else:
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
    elif kind == "wrist_wave":
        # a raised hand waving from the wrist: it turns about the wrist (0.25 hand lengths below the
        # palm centre) by +-20-40 degrees, so the palm barely travels and the fingertips swing
        swing = rng.uniform(20.0, 40.0)
        cycles = rng.uniform(2.0, 3.5)
        s = np.sin(2 * np.pi * cycles * u) * np.sin(np.pi * u) ** 0.3
        roll = swing * s
        a = np.deg2rad(roll)
        arm = 0.25
        path = np.stack([-arm * np.sin(a), arm * (1.0 - np.cos(a))], axis=1)
        path[:, 0] += rng.uniform(0.0, 0.08) * s  # the forearm sways a little
    elif kind == "checkmark":
        a = rng.uniform(0.8, 1.2)
        pts = np.array([[0.0, 0.0], [0.45, 0.6], [1.3, -0.9]]) * a
        path = _polyline(pts, u)
    elif kind == "zigzag":
        a = rng.uniform(0.8, 1.2)
        pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 0.7], [1.0, 0.7]]) * a
        path = _polyline(pts, u)
    elif kind in ("still", "raise_lower"):
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
    elif kind == "drift":
        # a slow drift of 0.3-2.7 hand lengths in any direction (u spans the clip)
        angle = rng.uniform(0.0, 2 * np.pi)
        travel = rng.uniform(0.3, 2.7)
        path = travel * ease(u)[:, None] * np.array([np.cos(angle), np.sin(angle)])
        path += rng.uniform(-0.2, 0.2) * np.sin(np.pi * u)[:, None] * np.array([-np.sin(angle), np.cos(angle)])
    elif kind == "close":
        # the hand closes into a fist (and opens again) while it drifts a little
        angle = rng.uniform(0.0, 2 * np.pi)
        path = rng.uniform(0.0, 0.4) * u[:, None] * np.array([np.cos(angle), np.sin(angle)])
    elif kind == "arm_arc":
        # loose arm movement: the hand swings along an arc about the elbow or shoulder, 2.5-4.5 hand
        # lengths away, 50-120 degrees, once or there and back
        radius = rng.uniform(2.5, 4.5)
        sweep = np.deg2rad(rng.uniform(50.0, 120.0)) * rng.choice([-1.0, 1.0])
        back = rng.random() < 0.5
        prog = np.sin(np.pi * u) if back else ease(u)
        base = np.deg2rad(rng.uniform(-50.0, 50.0)) - sweep / 2
        ang = base + sweep * prog
        # pivot below the hand: hand at pivot + radius * (sin a, -cos a)
        path = radius * np.stack([np.sin(ang) - np.sin(base), -(np.cos(ang) - np.cos(base))], axis=1)
        roll = -np.rad2deg(ang - base)
    else:
        raise ValueError("unknown motion %r" % kind)
    if kind not in NONE_KINDS:
        path = path @ rot.T
    return path, roll
