import numpy as np
import pytest

from rbd_local.gestures import synthetic
from rbd_local.gestures.overlay import POINT_BGR, draw_overlay
from rbd_local.gestures.sources import FrameSource


def test_overlay_draws_key_points_and_leaves_the_input_alone():
    frame = np.zeros((480, 640, 3), np.uint8)
    kp = synthetic.generate("static", np.random.default_rng(0))[0]
    out = draw_overlay(frame, kp, "wave", 0.9, sent="wiggle")
    assert not frame.any()
    for x, y in np.round(kp[:, :2]).astype(int):
        if 0 <= x < 640 and 0 <= y < 480:
            assert tuple(out[y, x]) == POINT_BGR
    assert out[:34].any()  # the caption bar with class and confidence
    assert draw_overlay(frame, None, "", 0.0).shape == frame.shape


def test_frame_source_arguments_and_missing_inputs(tmp_path):
    with pytest.raises(ValueError):
        FrameSource()
    with pytest.raises(ValueError):
        FrameSource(video="a.avi", images="b")
    with pytest.raises(OSError):
        FrameSource(images=str(tmp_path))
    with pytest.raises(OSError):
        FrameSource(video=str(tmp_path / "missing.avi"))


def test_image_sequence_is_timed_by_fps(tmp_path):
    import cv2

    for i in range(3):
        cv2.imwrite(str(tmp_path / ("%02d.png" % i)), np.full((48, 64, 3), i, np.uint8))
    (tmp_path / "notes.txt").write_text("not an image")
    src = FrameSource(images=str(tmp_path), fps=10.0)
    got = [(t, int(f[0, 0, 0])) for t, f in src]
    assert got == [(0.0, 0), (0.1, 1), (0.2, 2)]


def test_pipeline_survives_broken_frames(shipped_model):
    from rbd_local.gestures.config import load_config
    from rbd_local.gestures.pipeline import GesturePipeline

    sent = []
    pipe = GesturePipeline(shipped_model, load_config()["gestures"], send=sent.append)
    try:
        for i, bad in enumerate([np.zeros((4, 4), np.uint8), np.zeros((480, 640, 3), np.float64), np.zeros((0, 0, 3))]):
            r = pipe.process(i / 30.0, bad)
            assert r.keypoints is None and not r.decision.fired
        assert sent == []
    finally:
        pipe.close()


def test_realtime_playback_paces_files(tmp_path):
    import time

    import cv2

    for i in range(4):
        cv2.imwrite(str(tmp_path / ("%02d.png" % i)), np.zeros((8, 8, 3), np.uint8))
    t0 = time.monotonic()
    assert len(list(FrameSource(images=str(tmp_path), fps=10.0, realtime=True))) == 4
    assert time.monotonic() - t0 >= 0.29  # frames at 0, 0.1, 0.2, 0.3 s
