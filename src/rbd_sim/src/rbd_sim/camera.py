"""Simulated ZED2 left camera image: what the robot's camera shows, JPEG-compressed once.

ROS-free. The scene is a video file (for example a visitor performing a gesture in front of
the robot; tests and the demo use clips made from real hand photos) played at its own frame
rate and looped, or, without a video, a still placeholder picture. Every frame is resized and
JPEG-encoded once when the scene is loaded, so publishing costs no encoding at run time: the
node only picks the frame that belongs to the current time.

Needs OpenCV's Python binding (``cv2``: the workspace venv has it through mediapipe; on
Debian/Ubuntu ``python3-opencv``, which also exists for Python 3.6 / Melodic).
"""

import math

import numpy as np

#: The ZED2's VGA mode (per eye), the smallest it streams.
DEFAULT_SIZE = (672, 376)
#: What compressed_image_transport writes for a JPEG of a bgr8 image.
JPEG_FORMAT = "bgr8; jpeg compressed bgr8"


def placeholder_frame(width: int, height: int) -> np.ndarray:
    """A still picture for a camera without a scene video: a floor, a wall and a label.

    Args:
        width: image width [px].
        height: image height [px].

    Returns:
        (height, width, 3) uint8 BGR image.
    """
    import cv2

    img = np.empty((height, width, 3), np.uint8)
    horizon = int(height * 0.55)
    wall = np.linspace(200, 150, horizon).astype(np.uint8)
    img[:horizon] = wall[:, None, None]
    floor = np.linspace(110, 70, height - horizon).astype(np.uint8)
    img[horizon:] = floor[:, None, None]
    img[horizon:, :, 0] = np.clip(img[horizon:, :, 0].astype(int) + 25, 0, 255)
    cv2.putText(img, "rbd_sim ZED2 left (no scene video)", (12, 28), cv2.FONT_HERSHEY_SIMPLEX, 0.6,
                (40, 40, 40), 1, cv2.LINE_AA)
    return img


class CameraScene:
    """The frames of the simulated camera, JPEG-encoded, and which one shows at a given time.

    Args:
        video: path of a video file, or "" for the placeholder picture.
        width: output width [px] (0: the video's own size; the placeholder uses 672).
        height: output height [px] (0: the video's own size; the placeholder uses 376).
        quality: JPEG quality 1..100.
        max_frames: read at most this many frames of the video (a memory bound).

    Raises:
        ValueError: on bad sizes or quality, or a video that cannot be read or has no frame.
    """

    def __init__(self, video: str = "", width: int = 0, height: int = 0, quality: int = 80,
                 max_frames: int = 3000) -> None:
        import cv2

        if width < 0 or height < 0 or (width == 0) != (height == 0):
            raise ValueError("width and height must both be > 0, or both 0 (the video's own size)")
        if not 1 <= int(quality) <= 100:
            raise ValueError("jpeg quality must be in 1..100, got %r" % quality)
        params = [int(cv2.IMWRITE_JPEG_QUALITY), int(quality)]
        frames = []
        self.fps = 1.0
        if video:
            cap = cv2.VideoCapture(video)
            if not cap.isOpened():
                raise ValueError("cannot open scene video %r" % video)
            rate = cap.get(cv2.CAP_PROP_FPS)
            self.fps = float(rate) if rate and rate > 0 and math.isfinite(rate) else 30.0
            try:
                while len(frames) < max_frames:
                    ok, frame = cap.read()
                    if not ok or frame is None:
                        break
                    frames.append(frame)
            finally:
                cap.release()
            if not frames:
                raise ValueError("scene video %r has no frames" % video)
        else:
            frames = [placeholder_frame(width or DEFAULT_SIZE[0], height or DEFAULT_SIZE[1])]
        self.jpegs = []
        for frame in frames:
            if width and (frame.shape[1], frame.shape[0]) != (width, height):
                frame = cv2.resize(frame, (width, height), interpolation=cv2.INTER_AREA)
            ok, buf = cv2.imencode(".jpg", frame, params)
            if not ok:
                raise ValueError("JPEG encoding failed")
            self.jpegs.append(buf.tobytes())
        self.size = (frames[0].shape[1], frames[0].shape[0]) if not width else (width, height)

    def __len__(self) -> int:
        """Number of frames."""
        return len(self.jpegs)

    def index_at(self, elapsed: float) -> int:
        """Index of the frame shown ``elapsed`` seconds after the scene started (looping)."""
        if not elapsed > 0:
            return 0
        return int(elapsed * self.fps) % len(self.jpegs)

    def jpeg_at(self, elapsed: float) -> bytes:
        """The JPEG bytes shown ``elapsed`` seconds after the scene started."""
        return self.jpegs[self.index_at(elapsed)]
