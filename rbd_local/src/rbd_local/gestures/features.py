"""Normalised features of one window of hand key points.

The features are invariant to where the hand is in the image, how large it appears and
(mostly) how it is held, so that the linear classifier sees the motion: net displacement,
path shape, enclosed area, per-axis spectra and a few posture numbers, all in units of the
hand's own size (wrist to middle-finger base).
"""

import numpy as np

from rbd_local.gestures.hand import FINGER_TIPS, MIDDLE_MCP, NUM_LANDMARKS, PALM, WRIST

KEYFRAMES = 6
HARMONICS = 4
#: Width (standard deviation) of the palm path's smoothing kernel [window samples]; 0 turns it off.
SMOOTH_SAMPLES = 1.0

_SMOOTHERS = {}


def smoother(n: int, sigma: float) -> np.ndarray:
    """The (n, n) matrix of a local-linear Gaussian smoother for a path of n samples.

    Row i fits a straight line to the path by least squares with Gaussian weights of width
    ``sigma`` samples around sample i and takes the line's value at i. Inside the path this is
    a Gaussian blur; at both ends it is still unbiased for a steady motion (a plain blur would
    pull the ends inwards). It uses only the samples of the window, so it delays nothing.
    """
    key = (int(n), float(sigma))
    if key not in _SMOOTHERS:
        idx = np.arange(n, dtype=np.float64)
        if sigma <= 0 or n < 3:
            mat = np.eye(n)
        else:
            mat = np.empty((n, n))
            for i in range(n):
                d = idx - i
                w = np.exp(-0.5 * (d / sigma) ** 2)
                s0, s1, s2 = w.sum(), (w * d).sum(), (w * d * d).sum()
                # value at d = 0 of the weighted least-squares line through (d, x): sum_j a_j x_j
                mat[i] = w * (s2 - s1 * d) / (s0 * s2 - s1 * s1)
        _SMOOTHERS[key] = mat
    return _SMOOTHERS[key]


def palm_path(window: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The palm centre's smoothed path in hand sizes, starting at 0, and the hand size per frame.

    The palm centre is the mean of the wrist and the four finger bases; the hand size is the
    wrist to middle-finger base distance (its median over the window is the unit). The path is
    smoothed with :func:`smoother` (:data:`SMOOTH_SAMPLES`): a camera that shakes, or key points
    that jump from frame to frame, move the whole hand by a few pixels per frame, which a
    gesture's features (path length, reversals, turning) would otherwise count as motion.

    Args:
        window: (T, 21, >=2) key points in pixels, finite (not checked here).

    Returns:
        ((T, 2) path [hand sizes], (T,) hand size per frame [pixels]).

    Raises:
        ValueError: on a degenerate (zero-size) hand.
    """
    xy = window[:, :, :2]
    sizes = np.linalg.norm(xy[:, MIDDLE_MCP] - xy[:, WRIST], axis=1)
    size = float(np.median(sizes))
    if size < 1e-6:
        raise ValueError("degenerate hand: zero size")
    centre = xy[:, list(PALM)].mean(axis=1)
    path = smoother(len(centre), SMOOTH_SAMPLES) @ ((centre - centre[0]) / size)
    return path - path[0], sizes


def feature_names() -> list[str]:
    """Names of the entries of :func:`window_features`' output, in order."""
    names = ["dx", "dy", "path_len", "straightness", "area", "abs_area", "std_x", "std_y", "log_scale_change"]
    names += ["x%d" % i for i in range(KEYFRAMES)] + ["y%d" % i for i in range(KEYFRAMES)]
    names += ["fx%d" % k for k in range(1, HARMONICS + 1)] + ["fy%d" % k for k in range(1, HARMONICS + 1)]
    names += ["reversals_x", "reversals_y", "corr_xy", "turning", "turn_consistency", "peak_x", "peak_y"]
    names += ["ext%d" % f for f in range(5)] + ["ext_change", "orient_cos", "orient_sin"]
    names += ["swing_std", "swing_reversals", "swing_peak", "tip_swings"]
    return names


NUM_FEATURES = len(feature_names())


def hand_size(frame: np.ndarray) -> float:
    """Wrist to middle-finger base distance of one frame of key points [same unit as input]."""
    return float(np.linalg.norm(frame[MIDDLE_MCP, :2] - frame[WRIST, :2]))


def swings(v: np.ndarray, min_amplitude: float) -> int:
    """Number of reversals of ``v`` between extremes at least ``min_amplitude`` apart.

    A value that goes up, down and up again by at least the amplitude each time has 2 swings
    back (a wave of 1.5 cycles); a one-way motion has none, however noisy, as long as its
    noise stays below the amplitude.
    """
    v = np.asarray(v, dtype=np.float64)
    count, direction = 0, 0
    lo = hi = extreme = v[0] if len(v) else 0.0
    for x in v[1:]:
        if direction == 0:  # not yet moved by the amplitude either way
            lo, hi = min(lo, x), max(hi, x)
            if x - lo >= min_amplitude:
                direction, extreme = 1, x
            elif hi - x >= min_amplitude:
                direction, extreme = -1, x
        elif direction * (x - extreme) > 0:
            extreme = x
        elif abs(x - extreme) >= min_amplitude:
            count, direction, extreme = count + 1, -direction, x
    return count


def swing_angle(window: np.ndarray) -> np.ndarray:
    """The hand's angle about the wrist per frame, relative to its mean [rad], smoothed like the palm path.

    The angle of the line from the wrist to the middle finger's base: a wave from the wrist
    turns it back and forth while the palm barely travels.
    """
    xy = np.asarray(window, dtype=np.float64)[:, :, :2]
    orient = xy[:, MIDDLE_MCP] - xy[:, WRIST]
    ang = np.unwrap(np.arctan2(orient[:, 1], orient[:, 0]))
    ang = smoother(len(ang), SMOOTH_SAMPLES) @ ang
    return ang - ang.mean()


def _reversals(v: np.ndarray, min_step: float) -> float:
    signs = np.sign(v[np.abs(v) > min_step])
    return float(np.count_nonzero(signs[1:] != signs[:-1])) if len(signs) > 1 else 0.0


def window_features(window: np.ndarray) -> np.ndarray:
    """Compute the feature vector of one window.

    Args:
        window: (T, 21, 2 or 3) key points of T >= 4 evenly spaced frames, in pixels.

    Returns:
        (NUM_FEATURES,) float64 vector.

    Raises:
        ValueError: on a wrong shape, non-finite values or a degenerate (zero-size) hand.
    """
    w = np.asarray(window, dtype=np.float64)
    if w.ndim != 3 or w.shape[1] != NUM_LANDMARKS or w.shape[2] < 2 or w.shape[0] < 4:
        raise ValueError("window must be (T>=4, 21, 2|3), got %s" % (w.shape,))
    if not np.all(np.isfinite(w)):
        raise ValueError("window contains NaN or infinite key points")
    xy = w[:, :, :2]
    path, sizes = palm_path(w)
    n = len(path)
    d = path[-1]
    steps = np.diff(path, axis=0)
    length = float(np.linalg.norm(steps, axis=1).sum())
    straight = float(np.linalg.norm(d) / (length + 1e-6))
    c = path - path.mean(axis=0)
    area = 0.5 * float(np.sum(c[:-1, 0] * c[1:, 1] - c[1:, 0] * c[:-1, 1]))
    std = c.std(axis=0)
    scale_change = float(np.log(max(sizes[-3:].mean(), 1e-6) / max(sizes[:3].mean(), 1e-6)))
    idx = np.linspace(0, n - 1, KEYFRAMES).round().astype(int)
    spec = np.abs(np.fft.rfft(c, axis=0)) / n
    spec_k = np.zeros((HARMONICS, 2))
    m = min(HARMONICS, spec.shape[0] - 1)
    spec_k[:m] = spec[1 : m + 1]
    rev_x = _reversals(steps[:, 0], 0.05)
    rev_y = _reversals(steps[:, 1], 0.05)
    denom = float(np.sqrt((c[:, 0] ** 2).sum() * (c[:, 1] ** 2).sum()))
    corr = float((c[:, 0] * c[:, 1]).sum() / denom) if denom > 1e-9 else 0.0
    moving = np.linalg.norm(steps, axis=1) > 0.05
    heading = np.arctan2(steps[moving, 1], steps[moving, 0])
    turns = (np.diff(heading) + np.pi) % (2 * np.pi) - np.pi if len(heading) > 1 else np.zeros(1)
    turning = float(turns.sum() / (2 * np.pi))
    consistency = float(abs(turns.sum()) / (np.abs(turns).sum() + 1e-6))
    energy = spec[1:] ** 2
    peak = energy.max(axis=0) / (energy.sum(axis=0) + 1e-9) if len(energy) else np.zeros(2)
    tips = xy[:, list(FINGER_TIPS)] - xy[:, WRIST][:, None, :]
    ext_t = np.linalg.norm(tips, axis=2) / np.maximum(sizes[:, None], 1e-6)
    ext = ext_t.mean(axis=0)
    ext_change = float(np.abs(np.diff(ext_t.mean(axis=1))).sum())
    orient = xy[:, MIDDLE_MCP] - xy[:, WRIST]
    ang = np.arctan2(orient[:, 1], orient[:, 0])
    swing = swing_angle(w)
    sspec = np.abs(np.fft.rfft(swing)) ** 2
    swing_peak = float(sspec[1:].max() / (sspec[1:].sum() + 1e-9)) if len(sspec) > 1 else 0.0
    tips = xy[:, list(FINGER_TIPS)].mean(axis=1) - xy[:, WRIST]
    tip_x = smoother(n, SMOOTH_SAMPLES) @ (tips[:, 0] / max(float(np.median(sizes)), 1e-6))
    feats = np.concatenate(
        [
            d,
            [length, straight, area, abs(area), std[0], std[1], scale_change],
            c[idx, 0],
            c[idx, 1],
            spec_k[:, 0],
            spec_k[:, 1],
            [rev_x, rev_y, corr, turning, consistency, peak[0], peak[1]],
            ext,
            [ext_change, float(np.cos(ang).mean()), float(np.sin(ang).mean())],
            [float(swing.std()), float(swings(swing, np.deg2rad(12.0))), swing_peak,
             float(swings(tip_x, 0.25))],
        ]
    )
    return feats


def batch_features(windows: np.ndarray) -> np.ndarray:
    """Features of a stack of windows, (N, T, 21, 3) -> (N, NUM_FEATURES)."""
    return np.stack([window_features(w) for w in windows]) if len(windows) else np.empty((0, NUM_FEATURES))


def resample(times: np.ndarray, frames: np.ndarray, samples: int) -> np.ndarray:
    """Linearly resample unevenly timed frames to ``samples`` evenly spaced ones.

    Args:
        times: (K,) strictly increasing time stamps [s].
        frames: (K, 21, D) key points.
        samples: number of output frames.

    Returns:
        (samples, 21, D) array spanning times[0]..times[-1].
    """
    times = np.asarray(times, dtype=np.float64)
    frames = np.asarray(frames, dtype=np.float64)
    if len(times) < 2 or len(times) != len(frames):
        raise ValueError("need at least two frames with matching time stamps")
    grid = np.linspace(times[0], times[-1], samples)
    flat = frames.reshape(len(frames), -1)
    idx = np.clip(np.searchsorted(times, grid, side="right") - 1, 0, len(times) - 2)
    span = np.maximum(times[idx + 1] - times[idx], 1e-12)
    w = np.clip((grid - times[idx]) / span, 0.0, 1.0)[:, None]
    out = flat[idx] * (1.0 - w) + flat[idx + 1] * w
    return out.reshape((samples,) + frames.shape[1:])
