"""Video clips made from a real hand photo moved over time (for tests and benchmarks).

Drawn hands are not detected reliably, but a real photo that is shrunk and moved across the
frame with the background edges stretched is tracked in every frame; the known motion gives
the expected gesture.
"""

import numpy as np

MOTIONS = {
    "right": (1.0, 0.0),
    "left": (-1.0, 0.0),
    "down": (0.0, 1.0),
    "up": (0.0, -1.0),
    "still": (0.0, 0.0),
}


def moving_photo_frames(
    photo: np.ndarray,
    motion: str = "right",
    fps: float = 30.0,
    hold_s: float = 0.4,
    move_s: float = 0.8,
    distance: float = 0.35,
    scale: float = 0.6,
    size: tuple = (640, 480),
) -> list[np.ndarray]:
    """Frames of ``photo`` held still, moved in one direction, then held still again.

    Args:
        photo: BGR image of a hand.
        motion: one of :data:`MOTIONS`.
        fps: frame rate of the clip [1/s].
        hold_s: still time before and after the move [s].
        move_s: duration of the move [s].
        distance: travel as a fraction of the frame width.
        scale: photo size relative to the frame.
        size: (width, height) of the output frames.

    Returns:
        List of BGR uint8 frames.

    Raises:
        ValueError: on an unknown motion.
    """
    import cv2

    if motion not in MOTIONS:
        raise ValueError("motion must be one of %s, got %r" % (sorted(MOTIONS), motion))
    width, height = size
    base = cv2.resize(photo, (width, height))
    direction = np.array(MOTIONS[motion])
    n_hold = int(round(hold_s * fps))
    n_move = max(2, int(round(move_s * fps)))
    travel = distance * width
    start = np.array([width, height]) * (1.0 - scale) / 2.0 - direction * travel / 2.0
    offsets = [start] * n_hold
    for i in range(n_move):
        u = i / (n_move - 1)
        offsets.append(start + direction * travel * (u * u * (3 - 2 * u)))
    offsets += [offsets[-1]] * n_hold
    frames = []
    for off in offsets:
        m = np.array([[scale, 0.0, off[0]], [0.0, scale, off[1]]])
        frames.append(cv2.warpAffine(base, m, (width, height), borderMode=cv2.BORDER_REPLICATE))
    return frames


def write_clip(frames: list[np.ndarray], path: str, fps: float = 30.0) -> None:
    """Write frames to a video file (MJPG in .avi).

    Raises:
        OSError: if the video cannot be written.
    """
    import cv2

    h, w = frames[0].shape[:2]
    writer = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*"MJPG"), fps, (w, h))
    if not writer.isOpened():
        raise OSError("cannot write video %s" % path)
    try:
        for f in frames:
            writer.write(f)
    finally:
        writer.release()
