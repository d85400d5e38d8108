"""Recorded key-point sequences (``.npz``), as written by ``rbd-record`` and read by ``rbd-train``.

========================  ===================================================
key                       content
========================  ===================================================
``format``, ``version``   ``"rbd_local.recording"``, 1
``label``                 gesture class of the whole recording (or ``none``)
``times``                 (K,) frame times [s]
``keypoints``             (K, 21, 3) key points in pixels; NaN where no hand
``image_size``            (width, height) of the source frames
========================  ===================================================
"""

import numpy as np

from rbd_local.gestures import features

FORMAT = "rbd_local.recording"
VERSION = 1


def save_recording(path: str, label: str, times: np.ndarray, keypoints: np.ndarray, image_size: tuple) -> None:
    """Write one labelled recording."""
    times = np.asarray(times, dtype=np.float64)
    keypoints = np.asarray(keypoints, dtype=np.float64)
    if keypoints.shape != (len(times), 21, 3):
        raise ValueError("keypoints must be (K, 21, 3) with K = len(times)")
    with open(path, "wb") as fh:
        np.savez(fh, format=np.array(FORMAT), version=np.array(VERSION), label=np.array(label), times=times,
                 keypoints=keypoints, image_size=np.array(image_size))


def load_recording(path: str) -> tuple[str, np.ndarray, np.ndarray]:
    """Read a recording; returns (label, times, keypoints).

    Raises:
        ValueError: if the file is not a recording of a known version.
    """
    with np.load(path, allow_pickle=False) as data:
        if "format" not in data.files or str(data["format"]) != FORMAT:
            raise ValueError("%s is not an rbd_local recording" % path)
        if int(data["version"]) != VERSION:
            raise ValueError("%s: recording version %d unsupported" % (path, int(data["version"])))
        return str(data["label"]), data["times"].astype(np.float64), data["keypoints"].astype(np.float64)


def recording_windows(
    label: str, times: np.ndarray, keypoints: np.ndarray, window_s: float, samples: int, step_s: float = 0.1,
    keep_most_motion: int = 3,
) -> np.ndarray:
    """Cut a recording into classifier windows.

    Windows with a missing hand are skipped. For a gesture label only the ``keep_most_motion``
    windows with the longest hand path are kept (a clip holds one performance plus still time
    around it); for ``none`` every window is kept.

    Returns:
        (N, samples, 21, 3) windows.
    """
    out = []
    motion = []
    if len(times) < 2:
        return np.empty((0, samples, 21, 3))
    end_t = times[0] + window_s
    while end_t <= times[-1] + 1e-9:
        sel = (times >= end_t - window_s - 1e-9) & (times <= end_t + 1e-9)
        kp = keypoints[sel]
        if sel.sum() >= 4 and np.all(np.isfinite(kp)) and times[sel][-1] - times[sel][0] >= 0.9 * window_s:
            w = features.resample(times[sel], kp, samples)
            centre = w[:, 0, :2]
            out.append(w)
            motion.append(float(np.linalg.norm(np.diff(centre, axis=0), axis=1).sum()))
        end_t += step_s
    if not out:
        return np.empty((0, samples, 21, 3))
    windows = np.stack(out)
    if label != "none" and keep_most_motion > 0:
        windows = windows[np.argsort(motion)[::-1][:keep_most_motion]]
    return windows
