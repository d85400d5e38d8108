"""Configuration, recordings, rbd-record -> rbd-train, entry points."""

import os
import subprocess
import sys

import cv2
import numpy as np
import pytest
import yaml

from rbd_local.gestures import synthetic
from rbd_local.gestures.config import DEFAULT_MODEL, check_mapping, load_config
from rbd_local.gestures.model import GestureModel
from rbd_local.gestures.photo_clip import moving_photo_frames, write_clip
from rbd_local.recording import load_recording, recording_windows, save_recording

PKG_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ENV = dict(os.environ, PYTHONPATH=os.path.join(PKG_ROOT, "src"))
TRICKS = {"walk", "spin", "wiggle", "lie_down"}


def test_default_config_maps_four_gestures_to_the_four_tricks(shipped_model):
    cfg = load_config()
    assert set(cfg["gestures"]) == set(synthetic.GESTURES) == set(shipped_model.gestures)
    assert set(cfg["gestures"].values()) == TRICKS
    assert cfg["model"] == DEFAULT_MODEL and os.path.isfile(DEFAULT_MODEL)
    assert check_mapping(cfg["gestures"], shipped_model.classes) == []


@pytest.mark.parametrize(
    "content, match",
    [
        ({"gestures": {"none": "walk"}}, "none"),
        ({"gestures": {"wave": ""}}, "non-empty"),
        ({"threshold": 1.5}, "threshold"),
        ({"bridge": {"port": "x"}}, "bridge.port"),
        ({"colour": "red"}, "unknown keys"),
        ({"min_consecutive": 0}, "min_consecutive"),
    ],
)
def test_bad_config_is_a_clear_error(tmp_path, content, match):
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(content))
    with pytest.raises(ValueError, match=match):
        load_config(str(path))


def test_user_config_overrides_and_mapping_checked_against_model(tmp_path, shipped_model):
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump({"gestures": {"wave": "spin", "thumbs_up": "walk"}, "bridge": {"port": 9191}}))
    cfg = load_config(str(path))
    assert cfg["bridge"] == {"host": "127.0.0.1", "port": 9191}
    with pytest.raises(ValueError, match="thumbs_up"):
        check_mapping(cfg["gestures"], shipped_model.classes)
    assert check_mapping({"wave": "spin"}, shipped_model.classes) == ["circle", "push_down", "swipe_right"]


def test_recording_windows_keep_the_performance(tmp_path):
    pts = synthetic.stream(["static", "swipe_right", "static"], seed=1)
    times = np.array([t for t, _ in pts])
    kps = np.stack([k for _, k in pts])
    kps[5] = np.nan  # a frame without a hand
    path = str(tmp_path / "r.npz")
    save_recording(path, "swipe_right", times, kps, (640, 480))
    label, t2, k2 = load_recording(path)
    assert label == "swipe_right" and np.array_equal(np.isnan(k2), np.isnan(kps))
    w = recording_windows(label, t2, k2, 1.2, 24)
    assert w.shape == (3, 24, 21, 3) and np.all(np.isfinite(w))
    np.savez(str(tmp_path / "bad.npz"), x=np.zeros(2))
    with pytest.raises(ValueError):
        load_recording(str(tmp_path / "bad.npz"))


def test_record_then_train_on_recordings(tmp_path, hand_photos):
    photo = cv2.imread(hand_photos["handSrc.jpg"])
    recs = []
    for label, motion in (("swipe_right", "right"), ("none", "still")):
        clip = str(tmp_path / ("%s.avi" % motion))
        write_clip(moving_photo_frames(photo, motion, distance=0.4), clip)
        out = str(tmp_path / ("%s.npz" % label))
        proc = subprocess.run([sys.executable, "-m", "rbd_local.record", "--label", label, "--video", clip,
                               "--headless", "--out", out], env=ENV, capture_output=True, text=True, timeout=120)
        assert proc.returncode == 0, proc.stderr[-2000:]
        lab, times, kps = load_recording(out)
        assert lab == label and len(times) == 48 and np.isfinite(kps).all()
        recs.append(out)
    model_path = str(tmp_path / "m.npz")
    proc = subprocess.run([sys.executable, "-m", "rbd_local.train", "--synthetic", "--per-class", "60",
                           "--per-none-kind", "30", "--eval-per-class", "30", "--data"] + recs + ["--out", model_path],
                          env=ENV, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "false triggers on random motion" in proc.stdout and "true \\ decided" in proc.stdout
    m = GestureModel.load(model_path)
    assert "2 recordings" in m.provenance and "synthetic" in m.provenance


def test_train_without_data_is_an_error(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "rbd_local.train", "--out", str(tmp_path / "m.npz")], env=ENV,
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "--synthetic" in proc.stderr


def test_entry_points_exist():
    import importlib

    try:
        import tomllib
    except ModuleNotFoundError:  # Python < 3.11
        import tomli as tomllib

    meta = tomllib.loads(open(os.path.join(PKG_ROOT, "pyproject.toml")).read())
    scripts = meta["project"]["scripts"]
    assert set(scripts) == {"rbd-gesture", "rbd-gui", "rbd-record", "rbd-train", "rbd-teach", "rbd-evaluate"}
    for target in scripts.values():
        module, func = target.split(":")
        assert callable(getattr(importlib.import_module(module), func))


def test_evaluation_clip_cache_tracks_once_and_gives_the_same_key_points(tmp_path):
    from rbd_local import evaluation

    kp = np.arange(4 * 21 * 3, dtype=np.float64).reshape(4, 21, 3)
    kp[1] = np.nan  # a frame without a hand stays one
    calls = []

    def make():
        calls.append(1)
        return [evaluation.Clip("circle", np.array([0.0, 0.1, 0.2, 0.3]), kp, "15 fps"),
                evaluation.Clip("still", np.array([0.0, 0.5]), kp[:2], "15 fps")]

    first = evaluation.cached_clips(str(tmp_path), "key a", make)
    again = evaluation.cached_clips(str(tmp_path), "key a", make)
    assert len(calls) == 1 and [c.kind for c in again] == ["circle", "still"]
    np.testing.assert_array_equal(again[0].keypoints, first[0].keypoints)  # NaN where NaN
    np.testing.assert_array_equal(again[1].times, [0.0, 0.5])
    assert again[0].condition == "15 fps" and again[0].detected == 3
    evaluation.cached_clips(str(tmp_path), "key b", make)  # another key: tracked again
    evaluation.cached_clips("", "key a", make)  # no cache directory: always tracked
    assert len(calls) == 3
