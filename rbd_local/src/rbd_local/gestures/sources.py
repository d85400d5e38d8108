"""Frame sources: a camera, a video file or a folder / glob of images."""

import glob
import os
import time

import numpy as np


class FrameSource:
    """Iterates over (time [s], BGR frame) pairs.

    Video files and image sequences are timed by their frame rate (``fps``), cameras by the
    wall clock, so the classifier window always covers the same real duration.
    """

    def __init__(
        self, camera: int = None, video: str = None, images: str = None, fps: float = 30.0, realtime: bool = False
    ) -> None:
        """Open exactly one source.

        Args:
            camera: OpenCV camera index.
            video: path of a video file.
            images: a directory of images (sorted by name) or a glob pattern.
            fps: frame rate assumed for image sequences (and videos that do not tell).
            realtime: play files at their frame rate instead of as fast as possible.

        Raises:
            ValueError: if not exactly one source is given, or fps <= 0.
            OSError: if the source cannot be opened or is empty.
        """
        import cv2

        if sum(x is not None for x in (camera, video, images)) != 1:
            raise ValueError("give exactly one of camera, video, images")
        if not fps > 0:
            raise ValueError("fps must be > 0")
        self.fps = float(fps)
        self._cap = None
        self._files = None
        self.live = camera is not None
        self.realtime = bool(realtime)
        if images is not None:
            pattern = os.path.join(images, "*") if os.path.isdir(images) else images
            exts = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")
            self._files = sorted(f for f in glob.glob(pattern) if f.lower().endswith(exts))
            if not self._files:
                raise OSError("no images match %s" % images)
        else:
            if video is not None and not os.path.isfile(video):
                raise OSError("video file %s does not exist" % video)
            self._cap = cv2.VideoCapture(camera if camera is not None else video)
            if not self._cap.isOpened():
                raise OSError("cannot open %s" % (("camera %d" % camera) if camera is not None else video))
            if video is not None:
                rate = self._cap.get(cv2.CAP_PROP_FPS)
                if rate and rate > 0:
                    self.fps = float(rate)

    def __iter__(self) -> "FrameSource":
        """Iterate over frames."""
        self._index = 0
        self._t0 = time.monotonic()
        return self

    def __next__(self) -> tuple[float, np.ndarray]:
        """Next (time, frame); StopIteration at the end of a file or sequence."""
        t, frame = self._next()
        if self.realtime and not self.live:
            delay = t - (time.monotonic() - self._t0)
            if delay > 0:
                time.sleep(delay)
        return t, frame

    def _next(self) -> tuple[float, np.ndarray]:
        import cv2

        if self._files is not None:
            while self._index < len(self._files):
                frame = cv2.imread(self._files[self._index])
                self._index += 1
                if frame is not None:
                    return (self._index - 1) / self.fps, frame
            raise StopIteration
        ok, frame = self._cap.read()
        if not ok or frame is None:
            raise StopIteration
        self._index += 1
        t = time.monotonic() - self._t0 if self.live else (self._index - 1) / self.fps
        return t, frame

    def close(self) -> None:
        """Release the camera or file."""
        if self._cap is not None:
            self._cap.release()
            self._cap = None
