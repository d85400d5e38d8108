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
    scale: float = 0.3,
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
        scale: photo size relative to the frame. The photo's hand is about as long as the
            photo is wide: at the default 0.3 a travel of 0.4 of the width is about 1.5 hand
            lengths, a swipe the recognizer's travel check accepts (:mod:`.checks`). At 0.6 the
            same travel was 0.6-0.7 hand lengths: a near hand drifting (issue 26's failure mode
            4), which must not fire; real swipes travel 2.6-7 hand lengths.
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


class HandSprite:
    """The hand of a real photo, cut out and ready to be placed in a frame.

    It can be placed anywhere, at any size, roll angle and handedness. The photos of
    Debian's ``opencv-doc`` show a hand lying on a light grey table, wrist at the
    left edge, fingers pointing right. The hand is separated from the table by colour (skin is
    redder than the grey table), the wrist is extended to a forearm by repeating the photo's
    left edge, and the cut-out is turned so that at roll 0 the fingers point up and the forearm
    down, as a visitor holds a hand up towards the camera.
    """

    def __init__(self, photo: np.ndarray, forearm: float = 0.8) -> None:
        """Cut the hand out of ``photo``.

        Args:
            photo: BGR image of a hand on a plain, less red background, wrist at the left edge.
            forearm: forearm length added at the wrist, in hand lengths.

        Raises:
            ValueError: if no hand-coloured region touching the left edge is found.
        """
        import cv2

        img = np.asarray(photo)
        if img.ndim != 3 or img.shape[2] != 3 or img.dtype != np.uint8:
            raise ValueError("photo must be an (H, W, 3) uint8 BGR image")
        redness = img[:, :, 2].astype(np.int16) - img[:, :, 0].astype(np.int16)
        mask = (redness > 25).astype(np.uint8) * 255
        mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((5, 5), np.uint8))
        mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, np.ones((9, 9), np.uint8))
        count, labels, stats, _ = cv2.connectedComponentsWithStats(mask)
        if count < 2:
            raise ValueError("no hand found in the photo")
        biggest = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
        mask = np.where(labels == biggest, 255, 0).astype(np.uint8)
        # fill holes (palm lines and shadows that are less red)
        holes = mask.copy()
        ff = np.zeros((mask.shape[0] + 2, mask.shape[1] + 2), np.uint8)
        cv2.floodFill(holes, ff, (img.shape[1] - 1, img.shape[0] - 1), 255)
        mask = mask | cv2.bitwise_not(holes)
        rows = np.flatnonzero(mask[:, 0])
        if len(rows) < 10:
            raise ValueError("the hand in the photo does not reach the left edge (no wrist)")
        cols = np.flatnonzero(mask.any(axis=0))
        self.length = float(cols.max())  # wrist (left edge) to the farthest fingertip [px]
        arm = int(round(forearm * self.length))
        colour = np.concatenate([np.repeat(img[:, :1], arm, axis=1), img], axis=1)
        alpha = np.concatenate([np.repeat(mask[:, :1], arm, axis=1), mask], axis=1)
        alpha = cv2.GaussianBlur(alpha, (5, 5), 0)
        # palm centre: centroid of the hand pixels between the wrist and 45 % of the length
        ys, xs = np.nonzero(mask[:, : int(0.45 * self.length)])
        anchor = np.array([xs.mean() + arm, ys.mean()])
        # turn by -90 degrees: fingers up, forearm down
        self.colour = np.ascontiguousarray(np.rot90(colour, 1))
        self.alpha = np.ascontiguousarray(np.rot90(alpha, 1)).astype(np.float32) / 255.0
        self.anchor = np.array([anchor[1], colour.shape[1] - 1 - anchor[0]])  # (x, y) after the turn
        self.background = np.median(img[mask == 0], axis=0).astype(np.float32)

    def place(
        self, canvas: np.ndarray, centre: tuple, length_px: float, roll_deg: float = 0.0, left: bool = False,
        squash: float = 1.0, gain: float = 1.0,
    ) -> np.ndarray:
        """Draw the hand onto a copy of ``canvas``.

        Args:
            canvas: BGR background image (not modified).
            centre: (x, y) of the palm centre in the canvas [px].
            length_px: hand length (wrist to the longest fingertip) in the canvas [px].
            roll_deg: rotation in the image plane, positive counter-clockwise as seen [deg].
            left: mirror the hand (a left hand).
            squash: scale along the fingers about the palm centre (1: open hand; about 0.55: the
                fingers folded into a fist, as the camera sees a hand that closes).
            gain: factor on the hand's colour (below 1: a hand darker than the scene, backlight).

        Returns:
            The composed BGR image.
        """
        import cv2

        s = float(length_px) / self.length
        a = np.deg2rad(roll_deg)
        c, si = np.cos(a) * s, np.sin(a) * s
        mx = -1.0 if left else 1.0
        # sprite (x, y) -> canvas: mirror about the anchor, scale + rotate, then move to centre
        m = np.array([[c * mx, si], [-si * mx, c]]) @ np.diag([1.0, float(squash)])
        t = np.asarray(centre, dtype=np.float64) - m @ self.anchor
        affine = np.hstack([m, t[:, None]])
        h, w = canvas.shape[:2]
        # warp only into the bounding box of the sprite's corners (the rest stays the canvas)
        sh, sw = self.alpha.shape
        corners = np.array([[0, 0], [sw, 0], [0, sh], [sw, sh]], dtype=np.float64) @ m.T + t
        x0, y0 = np.maximum(np.floor(corners.min(axis=0)).astype(int) - 1, 0)
        x1, y1 = np.minimum(np.ceil(corners.max(axis=0)).astype(int) + 1, [w, h])
        out = canvas.copy()
        if x1 <= x0 or y1 <= y0:
            return out
        affine = np.hstack([m, (t - np.array([x0, y0]))[:, None]])
        size = (int(x1 - x0), int(y1 - y0))
        colour = cv2.warpAffine(self.colour, affine, size, flags=cv2.INTER_AREA if s < 1 else cv2.INTER_LINEAR,
                                borderMode=cv2.BORDER_CONSTANT)
        alpha = cv2.warpAffine(self.alpha, affine, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
        roi = out[y0:y1, x0:x1].astype(np.float32)
        a = alpha[:, :, None]
        if gain != 1.0:
            colour = colour.astype(np.float32) * float(gain)
        out[y0:y1, x0:x1] = np.clip(roi + (colour.astype(np.float32) - roi) * a, 0, 255).astype(np.uint8)
        return out

    def plain_background(self, size: tuple = (640, 480)) -> np.ndarray:
        """A background of the photo's own table colour with a soft light gradient."""
        w, h = size
        ramp = np.linspace(0.9, 1.05, h, dtype=np.float32)[:, None, None] * np.linspace(
            1.03, 0.95, w, dtype=np.float32)[None, :, None]
        return np.clip(self.background[None, None, :] * ramp, 0, 255).astype(np.uint8)
