"""Real hand photos through MediaPipe, and moving-photo clips through the whole pipeline."""

import json
import os
import subprocess
import sys

import cv2
import numpy as np
import pytest

from rbd_local.gestures.config import load_config
from rbd_local.gestures.detector import HandDetector
from rbd_local.gestures.hand import FINGER_TIPS, MIDDLE_MCP, WRIST
from rbd_local.gestures.photo_clip import moving_photo_frames, write_clip
from rbd_local.gestures.pipeline import GesturePipeline

PKG_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture(scope="module")
def photos(hand_photos):
    return {name: cv2.imread(path) for name, path in hand_photos.items()}


@pytest.mark.parametrize("name", ["handSrc.jpg", "handDst.jpg"])
def test_real_photo_gives_21_plausible_landmarks(photos, name):
    img = photos[name]
    assert img is not None and img.shape == (480, 640, 3)
    with HandDetector(static_image=True) as det:
        found = det.detect(img)
    assert found is not None, "no hand found in a real hand photo"
    kp, score = found
    assert kp.shape == (21, 3) and score > 0.5
    h, w = img.shape[:2]
    assert np.all(kp[:, 0] > -0.05 * w) and np.all(kp[:, 0] < 1.05 * w)
    assert np.all(kp[:, 1] > -0.05 * h) and np.all(kp[:, 1] < 1.05 * h)
    # The photos show a hand lying flat, wrist at the left edge, fingers pointing right.
    assert kp[WRIST, 0] < 0.15 * w
    tips = kp[list(FINGER_TIPS[1:])]
    assert np.all(tips[:, 0] > kp[MIDDLE_MCP, 0])
    # Each finger's tip is farther from the wrist than its base joint; the hand is big in frame.
    for base, tip in ((5, 8), (9, 12), (13, 16), (17, 20)):
        assert np.linalg.norm(kp[tip, :2] - kp[WRIST, :2]) > np.linalg.norm(kp[base, :2] - kp[WRIST, :2])
    size = np.linalg.norm(kp[MIDDLE_MCP, :2] - kp[WRIST, :2])
    assert 0.2 * w < size < 0.8 * w


def test_landmarks_follow_a_shifted_photo(photos):
    img = photos["handSrc.jpg"]
    shift = np.float32([[0.7, 0, 120], [0, 0.7, 60]])
    moved = cv2.warpAffine(img, shift, (640, 480), borderMode=cv2.BORDER_REPLICATE)
    with HandDetector(static_image=True) as det:
        a = det.detect(img)[0]
        b = det.detect(moved)[0]
    expected = a[:, :2] * 0.7 + np.array([120.0, 60.0])
    err = np.linalg.norm(b[:, :2] - expected, axis=1)
    assert np.median(err) < 12.0, err


def test_detector_rejects_bad_images_and_finds_no_hand_in_a_blank_one():
    with HandDetector(static_image=True) as det:
        with pytest.raises(ValueError):
            det.detect(np.zeros((10, 10), np.uint8))
        with pytest.raises(ValueError):
            det.detect(np.zeros((48, 64, 3), np.float32))
        assert det.detect(np.full((480, 640, 3), 200, np.uint8)) is None


def _run_clip(model, photo, motion):
    sent = []
    cfg = load_config()
    pipe = GesturePipeline(model, cfg["gestures"], send=sent.append, model_complexity=cfg["model_complexity"])
    tracked = 0
    try:
        frames = moving_photo_frames(photo, motion, fps=30.0, hold_s=0.4, move_s=0.8, distance=0.4)
        for i, f in enumerate(frames + [frames[-1]] * 12):
            r = pipe.process(i / 30.0, f)
            tracked += r.keypoints is not None
    finally:
        pipe.close()
    return sent, tracked, len(frames) + 12


@pytest.mark.parametrize(
    "motion, expected",
    [("right", ["walk"]), ("down", ["lie_down"]), ("left", []), ("up", []), ("still", [])],
)
def test_moving_photo_clip_through_the_whole_pipeline(shipped_model, photos, motion, expected):
    sent, tracked, total = _run_clip(shipped_model, photos["handSrc.jpg"], motion)
    assert tracked == total, "the hand must be tracked in every frame"
    assert sent == expected


def test_rbd_gesture_cli_on_a_video_file_and_an_image_sequence(tmp_path, photos):
    frames = moving_photo_frames(photos["handDst.jpg"], "right", distance=0.4, hold_s=0.6)
    clip = str(tmp_path / "right.avi")
    write_clip(frames, clip)
    img_dir = tmp_path / "seq"
    img_dir.mkdir()
    for i, f in enumerate(frames):
        cv2.imwrite(str(img_dir / ("%04d.jpg" % i)), f)
    env = dict(os.environ, PYTHONPATH=os.path.join(PKG_ROOT, "src"))
    for source in (["--video", clip], ["--images", str(img_dir)]):
        proc = subprocess.run(
            [sys.executable, "-m", "rbd_local.gesture_app", "--headless", "--no-link"] + source,
            capture_output=True, universal_newlines=True, timeout=120, env=env,
        )
        assert proc.returncode == 0, proc.stderr[-2000:]
        lines = [json.loads(x) for x in proc.stdout.splitlines() if x.startswith("{")]
        assert [x["command"] for x in lines] == ["walk"], proc.stdout
        assert lines[0]["gesture"] == "swipe_right" and lines[0]["confidence"] >= 0.8


def test_rbd_gesture_cli_reports_a_missing_video_clearly(tmp_path):
    env = dict(os.environ, PYTHONPATH=os.path.join(PKG_ROOT, "src"))
    proc = subprocess.run(
        [sys.executable, "-m", "rbd_local.gesture_app", "--headless", "--no-link", "--video", str(tmp_path / "x.avi")],
        capture_output=True, universal_newlines=True, timeout=60, env=env,
    )
    assert proc.returncode == 2 and "does not exist" in proc.stderr
