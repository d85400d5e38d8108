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


def feature_names() -> list[str]:
    """Names of the entries of :func:`window_features`' output, in order."""
    names = ["dx", "dy", "path_len", "straightness", "area", "abs_area", "std_x", "std_y", "log_scale_change"]
    names += ["x%d" % i for i in range(KEYFRAMES)] + ["y%d" % i for i in range(KEYFRAMES)]
    names += ["fx%d" % k for k in range(1, HARMONICS + 1)] + ["fy%d" % k for k in range(1, HARMONICS + 1)]
    names += ["reversals_x", "reversals_y", "corr_xy", "turning", "turn_consistency", "peak_x", "peak_y"]
    names += ["ext%d" % f for f in range(5)] + ["ext_change", "orient_cos", "orient_sin"]
    return names


NUM_FEATURES = len(feature_names())


def hand_size(frame: np.ndarray) -> float:
    """Wrist to middle-finger base distance of one frame of key points [same unit as input]."""
    return float(np.linalg.norm(frame[MIDDLE_MCP, :2] - frame[WRIST, :2]))


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
    sizes = np.linalg.norm(xy[:, MIDDLE_MCP] - xy[:, WRIST], axis=1)
    size = float(np.median(sizes))
    if size < 1e-6:
        raise ValueError("degenerate hand: zero size")
    centre = xy[:, list(PALM)].mean(axis=1)
    path = (centre - centre[0]) / size
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
