"""The simulated ZED2 left camera's scene (ROS-free): frames, looping, JPEG, bad parameters."""

import cv2
import numpy as np
import pytest

from rbd_sim.camera import DEFAULT_SIZE, CameraScene


def _video(path, n=20, fps=10.0, size=(160, 120)):
    """A test video: frame i is a flat grey of value 10 * i (so a decoded frame tells its index)."""
    out = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps, size)
    assert out.isOpened()
    for i in range(n):
        out.write(np.full((size[1], size[0], 3), 10 * i, np.uint8))
    out.release()
    return str(path)


def _decode(jpeg):
    img = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
    assert img is not None
    return img


def test_video_frames_play_at_the_videos_rate_and_loop(tmp_path):
    scene = CameraScene(_video(tmp_path / "v.avi"))
    assert len(scene) == 20 and scene.fps == pytest.approx(10.0) and scene.size == (160, 120)
    # 0.35 s after the start the fourth frame (index 3) shows; after 2.05 s (20 frames) it loops
    assert abs(float(_decode(scene.jpeg_at(0.35)).mean()) - 30.0) < 3.0
    assert abs(float(_decode(scene.jpeg_at(2.05)).mean()) - 0.0) < 3.0
    assert abs(float(_decode(scene.jpeg_at(2.15)).mean()) - 10.0) < 3.0
    assert scene.index_at(-1.0) == 0


def test_frames_are_resized_when_asked(tmp_path):
    scene = CameraScene(_video(tmp_path / "v.avi", n=3), width=64, height=48, quality=50)
    assert _decode(scene.jpeg_at(0.0)).shape == (48, 64, 3)


def test_placeholder_without_a_video_has_the_zed2_vga_size():
    scene = CameraScene("")
    assert len(scene) == 1
    img = _decode(scene.jpeg_at(123.4))
    assert img.shape == (DEFAULT_SIZE[1], DEFAULT_SIZE[0], 3)
    assert img.std() > 5  # a picture, not a flat frame


@pytest.mark.parametrize("kwargs, text", [
    ({"video": "/nonexistent.avi"}, "cannot open"),
    ({"width": 100}, "both"),
    ({"quality": 0}, "quality"),
])
def test_bad_parameters_are_clear_errors(kwargs, text):
    with pytest.raises(ValueError, match=text):
        CameraScene(**kwargs)
