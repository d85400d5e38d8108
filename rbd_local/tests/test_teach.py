"""Teach mode: a gesture taught from real-photo clips, recognised on new ones, kept in the file.

Clips are made from the real hand photos of opencv-doc (rbd_local.gestures.realclips) at
0.7-1.3 m, left and right hands, 30 fps. Teaching goes through ``rbd-teach --clips`` (MediaPipe
on the written video files, the model file saved); recognition of the 20 new clips, the
built-in gestures and random motion replays each clip's MediaPipe key points (tracked once per
session) through the app's recogniser with the model *loaded from that file*; one new clip
also goes through ``rbd-gesture`` in a fresh process (the whole pipeline, MediaPipe included).
"""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from rbd_local import evaluation
from rbd_local.gestures import fewshot, realclips, synthetic
from rbd_local.gestures.model import NONE, GestureModel, TeachConflictError
from rbd_local.gestures.photo_clip import write_clip
from rbd_local.gestures.teach import TeachSession, extract_show

PKG_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ENV = dict(os.environ, PYTHONPATH=os.path.join(PKG_ROOT, "src"))
TAUGHT = "checkmark"
TRICK = "bow"


@pytest.fixture(scope="module")
def clips(hand_sprites):
    """Tracked clips: 20 new checkmarks, 5 of each built-in gesture, 6 random motions (4 s).

    One hand is tracked (``max_hands=1``): these clips show one hand, and MediaPipe asked for two
    runs its palm detector on every frame (about 3 times the time). Two hands are tested in
    test_real_world.py and by ``rbd-teach --clips`` in :func:`taught_file` (the app's detector).
    """
    from rbd_local.gestures.detector import HandDetector

    plan = {TAUGHT: 20, "swipe_right": 5, "circle": 5, "wave": 5, "push_down": 5, "still": 2, "wander": 2,
            "random_points": 2}
    with HandDetector(model_complexity=0, max_hands=1) as det:
        return evaluation.make_clips(hand_sprites, plan, realclips.BASELINE, seed=2020, detector=det)


@pytest.fixture(scope="module")
def taught_file(tmp_path_factory, hand_sprites, shipped_model):
    """``rbd-teach --clips`` on five checkmark clips; returns (model file, clip dir)."""
    d = tmp_path_factory.mktemp("teach")
    rng = np.random.default_rng(77)
    paths = []
    for i in range(5):
        _times, frames = realclips.make_clip(hand_sprites, TAUGHT, realclips.BASELINE, rng)
        paths.append(str(d / ("show%d.avi" % i)))
        write_clip(frames, paths[-1])
    model = str(d / "model.npz")
    proc = subprocess.run([sys.executable, "-m", "rbd_local.teach_app", "--name", TAUGHT, "--trick", TRICK,
                           "--model", model, "--clips"] + paths, env=ENV, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr[-3000:]
    report = json.loads(proc.stdout.splitlines()[0])
    assert report["shows"] == 5 and report["built_in"] == {}, report
    return model, d


def test_rbd_teach_clips_with_too_few_usable_shows_fails_and_says_which(taught_file, tmp_path):
    # issue 26: 5 files of which 2 show no hand at all -> not taught, exit 1, the count and the files named
    _model, d = taught_file
    shows = [str(d / ("show%d.avi" % i)) for i in range(3)]
    blank = [str(tmp_path / ("empty%d.avi" % i)) for i in range(2)]
    for path in blank:
        write_clip([np.full((480, 640, 3), 128, np.uint8)] * 45, path)
    model = str(tmp_path / "model.npz")
    proc = subprocess.run([sys.executable, "-m", "rbd_local.teach_app", "--name", "late", "--trick", TRICK,
                           "--model", model, "--clips"] + shows + blank, env=ENV, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 1, proc.stdout + proc.stderr[-3000:]
    assert "usable 3 of 5, need 4" in proc.stderr, proc.stderr[-3000:]
    assert all("no usable show in %s: no hand seen" % b in proc.stderr for b in blank), proc.stderr[-3000:]
    assert not os.path.exists(model)  # nothing taught, nothing written


def test_taught_gesture_recognised_builtins_kept_random_motion_ignored(taught_file, clips):
    model = GestureModel.load(taught_file[0])  # a fresh load of the file: what a restart sees
    assert model.taught.names == [TAUGHT] and model.taught_commands() == {TAUGHT: TRICK}
    assert model.revision == 1 and "checkmark" in model.history[0]
    frames = sum(len(c.times) for c in clips)
    assert sum(c.detected for c in clips) >= 0.98 * frames, "MediaPipe lost the hand in the baseline clips"
    expected = {k: k for k in realclips.BUILT_IN}
    expected[TAUGHT] = TAUGHT
    res = evaluation.score(model, clips, expected)
    taught_ok, taught_n = res["by_kind"][TAUGHT]
    assert taught_n == 20 and taught_ok >= 18, res["fired"][TAUGHT]
    built_ok = sum(res["by_kind"][k][0] for k in realclips.BUILT_IN)
    built_n = sum(res["by_kind"][k][1] for k in realclips.BUILT_IN)
    assert built_n == 20 and built_ok >= 19, {k: res["fired"][k] for k in realclips.BUILT_IN}
    assert res["random_windows"] > 300
    assert res["random_false_windows"] <= 0.02 * res["random_windows"], res["fired"]
    # the same clips without the taught gesture: the checkmarks are not recognised at all
    plain = GestureModel.load(taught_file[0])
    plain.forget(TAUGHT)
    res0 = evaluation.score(plain, [c for c in clips if c.kind == TAUGHT], {TAUGHT: TAUGHT})
    assert res0["correct"] == 0, res0["fired"]


@pytest.fixture(scope="module")
def hard_clips(hand_sprites):
    """Tracked clips the shipped model used to miss: camera shake of 4 px (2 of each built-in gesture,
    4 checkmarks, a still hand and wandering for 4 s each), and circles drawn in 0.6 s (baseline);
    one hand tracked, as in :func:`clips`."""
    from rbd_local.gestures.detector import HandDetector

    shake = [c for c in realclips.CONDITIONS if c.name.startswith("camera shake")][0]
    assert shake.shake_px >= 4.0
    plan = {"swipe_right": 2, "circle": 2, "wave": 2, "push_down": 2, TAUGHT: 4, "still": 1, "wander": 1}
    rng = np.random.default_rng(2424)
    with HandDetector(model_complexity=0, max_hands=1) as det:
        shaky = evaluation.make_clips(hand_sprites, plan, shake, seed=2424, detector=det)
        fast = []
        for _ in range(4):
            times, frames = realclips.make_clip(hand_sprites, "circle", realclips.BASELINE, rng, motion_s=0.6)
            fast.append(evaluation.Clip("circle", times, realclips.track_clip(det, frames), "fast circles"))
    return shaky, fast


def test_camera_shake_and_fast_circles(taught_file, hard_clips):
    # Before the palm path was smoothed and the model retrained with faster motions, the evaluation
    # recognised 12 of 24 built-in gestures under this shake and 3 of 10 circles drawn in 0.6 s.
    shaky, fast = hard_clips
    model = GestureModel.load(taught_file[0])
    assert sum(c.detected for c in shaky) >= 0.98 * sum(len(c.times) for c in shaky), "hand lost in shaky clips"
    expected = {k: k for k in realclips.BUILT_IN}
    expected[TAUGHT] = TAUGHT
    res = evaluation.score(model, shaky, expected)
    built_ok = sum(res["by_kind"][k][0] for k in realclips.BUILT_IN)
    assert built_ok >= 7, {k: res["fired"][k] for k in realclips.BUILT_IN}
    assert res["by_kind"][TAUGHT][0] >= 3, res["fired"][TAUGHT]
    assert res["random_windows"] > 150  # the input arrived: full windows of shaky random motion were decided
    assert res["random_false_windows"] <= 0.02 * res["random_windows"], res["fired"]
    fast_res = evaluation.score(model, fast, {"circle": "circle"})
    assert fast_res["correct"] >= 3, fast_res["fired"]


def test_taught_gesture_survives_a_restart_through_rbd_gesture(taught_file, hand_sprites):
    model, d = taught_file
    _times, frames = realclips.make_clip(hand_sprites, TAUGHT, realclips.BASELINE, np.random.default_rng(4040))
    clip = str(d / "new.avi")
    write_clip(frames + [frames[-1]] * 10, clip)
    proc = subprocess.run([sys.executable, "-m", "rbd_local.gesture_app", "--headless", "--no-link", "--video", clip,
                           "--model", model], env=ENV, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    lines = [json.loads(x) for x in proc.stdout.splitlines() if x.startswith("{")]
    assert [(x["gesture"], x["command"]) for x in lines] == [(TAUGHT, TRICK)], proc.stdout


def test_forget_and_undo_through_rbd_teach(taught_file, tmp_path):
    import shutil

    model = str(tmp_path / "m.npz")
    shutil.copyfile(taught_file[0], model)

    def teach(*args):
        return subprocess.run([sys.executable, "-m", "rbd_local.teach_app", "--model", model] + list(args), env=ENV,
                              capture_output=True, text=True, timeout=120)

    assert "checkmark -> bow (5 shows)" in teach("--list").stdout
    assert teach("--forget", TAUGHT).returncode == 0
    assert GestureModel.load(model).taught.names == [] and GestureModel.load(model).revision == 2
    assert teach("--forget", TAUGHT).returncode == 2  # not taught any more: a clear error
    assert teach("--undo").returncode == 0
    assert GestureModel.load(model).taught.names == [TAUGHT]
    assert teach("--undo").returncode == 2  # one step of undo only


# ------------------------------------------------------------------ fast unit tests (no MediaPipe)
def _windows(kind, n, seed):
    rng = np.random.default_rng(seed)
    return np.stack([synthetic.generate(kind, rng) for _ in range(n)])


def test_embedding_ignores_where_and_how_big_the_hand_is_and_sees_direction():
    w = _windows("swipe_left", 1, 1)[0]
    moved = w.copy()
    moved[:, :, :2] = moved[:, :, :2] * 0.4 + np.array([100.0, -30.0])
    np.testing.assert_allclose(fewshot.embed(moved), fewshot.embed(w), atol=1e-9)
    flipped = w.copy()
    flipped[:, :, 0] = -flipped[:, :, 0]  # a swipe right
    assert fewshot.distances(fewshot.embed(w), fewshot.embed(flipped)[None])[0] > 1.0
    with pytest.raises(ValueError):
        fewshot.embed(np.full((24, 21, 3), np.nan))


def test_taught_set_recognises_its_gesture_and_rejects_the_rest(shipped_model):
    # Ten sets of 5 shows each, every set tried on 30 new windows. The synthetic swipes up span
    # 1-5 hand lengths and 0.24-1.2 s (issue 26), so 5 random shows cover that range unevenly:
    # recall measured 0.70-0.93 per set, 0.83 over the ten (one set of the generator before
    # issue 26 passed a bar of 0.9 by its seed alone: 0.66 over ten sets). Taught from a
    # visitor's real-photo shows the bar is 18 of 20 (test_taught_gesture_recognised_...).
    recall, false = [], {}
    for seed in range(2, 12):
        taught = fewshot.TaughtGestures(shipped_model.samples)
        taught.add("swipe_up", "sit", _windows("swipe_up", 5, seed))
        hits = [taught.classify(w)[0] for w in _windows("swipe_up", 30, seed + 100)]
        recall.append(np.mean(np.array(hits) == "swipe_up"))
        for kind in ("static", "random_walk", "random_points", "swipe_right", "push_down", "swipe_left"):
            labels = [taught.classify(w)[0] for w in _windows(kind, 10, seed + 200)]
            false.setdefault(kind, []).extend(labels)
    assert np.mean(recall) >= 0.75 and min(recall) >= 0.6, recall
    for kind, labels in false.items():
        assert np.mean(np.array(labels) != NONE) <= 0.05, (kind, labels)
    with pytest.raises(ValueError):
        taught.add("x", "sit", _windows("swipe_up", 2, 5))  # fewer than 3 shows
    with pytest.raises(ValueError):
        taught.add("none", "sit", _windows("swipe_up", 3, 5))


def test_teaching_a_built_in_gesture_is_refused_unless_forced(tmp_path, shipped_model):
    path = str(tmp_path / "m.npz")
    shipped_model.save(path)
    model = GestureModel.load(path)
    with pytest.raises(TeachConflictError, match="swipe_right"):
        model.teach("my_swipe", "bow", _windows("swipe_right", 5, 6))
    assert model.taught.names == [] and model.revision == 0
    with pytest.raises(ValueError):
        model.teach("wave", "bow", _windows("swipe_up", 5, 6))  # a built-in class name
    model.teach("my_swipe", "bow", _windows("swipe_right", 5, 6), force=True)
    model.save(path)
    again = GestureModel.load(path)
    assert again.taught.names == ["my_swipe"] and again.revision == 1
    np.testing.assert_allclose(again.taught.windows["my_swipe"], model.taught.windows["my_swipe"])


def test_version_1_files_still_load(tmp_path, shipped_model):
    from rbd_local.gestures.config import DEFAULT_MODEL

    # a version-1 file: the keys of format 1 only (no revision, history or taught gestures)
    v2_only = ("revision", "history") + tuple(k for k in np.load(DEFAULT_MODEL).files if k.startswith("taught_"))
    with np.load(DEFAULT_MODEL) as data:
        v1 = {k: data[k] for k in data.files if k not in v2_only}
    v1["version"] = np.array(1)
    path = str(tmp_path / "v1.npz")
    np.savez(path, **v1)
    model = GestureModel.load(path)
    assert model.taught.names == [] and model.revision == 0 and model.history == []
    np.testing.assert_allclose(model.coef, shipped_model.coef)
    assert shipped_model.taught.names == [] and shipped_model.revision == 0


def test_extract_show_finds_the_whole_performance():
    frames = [kp for _t, kp in synthetic.stream(["static", "swipe_up", "static"], seed=5)]
    times = np.arange(len(frames)) / 30.0
    kps = np.stack(frames)
    w = extract_show(times, kps, 1.2, 24)
    assert w is not None and w.shape == (24, 21, 3)
    palm_y = w[:, 0, 1]
    assert palm_y[0] - palm_y[-1] > 1.5 * np.linalg.norm(w[0, 9, :2] - w[0, 0, :2])  # the whole swipe up
    still = np.stack([kp for _t, kp in synthetic.stream(["static", "static"], seed=5)])
    assert extract_show(np.arange(len(still)) / 30.0, still, 1.2, 24) is None


def test_teach_session_asks_again_after_a_show_without_motion(shipped_model, tmp_path):
    path = str(tmp_path / "m.npz")
    shipped_model.save(path)
    model = GestureModel.load(path)
    session = TeachSession(model, "swipe_up", "sit", shows=3, ready_s=0.5, show_s=2.0)
    # one continuous hand: still for the first show (nothing to learn), then a swipe up every 2.4 s
    for t, kp in synthetic.stream(["static", "static"] + ["swipe_up", "static"] * 6, seed=3):
        session.feed(t, kp)
        if not session.active:
            break
    assert session.phase == "done", session.message
    assert session.attempts >= 4 and len(session.windows) == 3
    assert "swipe_up" in model.taught.names and model.taught.commands["swipe_up"] == "sit"


def test_pipeline_sends_nothing_while_teaching(shipped_model, tmp_path):
    from rbd_local.gestures.pipeline import GesturePipeline

    class NoDetector:
        def __init__(self):
            self.frames = iter(synthetic.stream(["static", "swipe_right", "static"] * 4, seed=9))

        def detect(self, _frame):
            return next(self.frames)[1], 1.0

        def close(self):
            pass

    path = str(tmp_path / "m.npz")
    shipped_model.save(path)
    model = GestureModel.load(path)
    sent = []
    pipe = GesturePipeline(model, {"swipe_right": "walk"}, send=sent.append, detector=NoDetector())
    session = TeachSession(model, "other", "bow", shows=3, ready_s=0.1, show_s=1.5, force=True)
    pipe.start_teach(session)
    frame = np.zeros((4, 4, 3), np.uint8)
    n = 0
    while session.active and n < 400:
        pipe.process(n / 30.0, frame)
        n += 1
    assert n > 100 and sent == [], "a gesture was sent while teaching"
    assert session.phase == "done"
    for i in range(n, n + 150):
        pipe.process(i / 30.0, frame)
    assert sent, "after teaching, recognition resumes"


class _StreamDetector:
    """Stands in for MediaPipe: hands out the key points of a synthetic stream, one per frame."""

    def __init__(self, kinds, seed):
        self.frames = iter(synthetic.stream(kinds, seed=seed))

    def detect(self, _frame):
        return next(self.frames)[1], 1.0

    def close(self):
        pass


def _desk_pipeline(shipped_model, tmp_path, kinds, sent):
    from rbd_local.gestures.pipeline import GesturePipeline
    from rbd_local.gestures.teach import TeachDesk

    path = str(tmp_path / "user.npz")
    shipped_model.save(path)
    pipe = GesturePipeline(GestureModel.load(path), {"swipe_right": "walk"}, send=sent.append,
                           detector=_StreamDetector(kinds, seed=3))
    return TeachDesk(path, ready_s=0.5, show_s=2.0), pipe, path


def _run(desk, pipe, frames, start=0):
    frame = np.zeros((4, 4, 3), np.uint8)
    for i in range(start, start + frames):
        desk.step(pipe)
        pipe.process(i / 30.0, frame)
    return start + frames


def test_teach_desk_teaches_saves_forgets_and_undoes(shipped_model, tmp_path):
    sent = []
    kinds = ["static", "static"] + ["swipe_up", "static"] * 8
    desk, pipe, path = _desk_pipeline(shipped_model, tmp_path, kinds, sent)
    desk.step(pipe)
    assert desk.status()["phase"] == "idle" and desk.status()["taught"] == []
    desk.start("swipe_up", "sit", 3)
    with pytest.raises(ValueError, match="already running"):
        desk.start("other", "bow", 3)
    n = 0
    while desk.status()["phase"] in ("starting", "ready", "show") and n < 1500:
        n = _run(desk, pipe, 1, n)
    st = desk.status()
    assert st["phase"] == "done" and "saved" in st["message"], st
    assert st["good"] == 3 and st["taught"] == [("swipe_up", "sit", 3)]
    assert sent == [] and n > 3 * 2.5 * 30, "shows went through the pipeline and nothing was sent"
    saved = GestureModel.load(path)
    assert saved.taught_commands() == {"swipe_up": "sit"} and saved.revision == 1
    # forget: saved at once, the pipeline's model no longer knows it
    desk.forget("swipe_up")
    n = _run(desk, pipe, 1, n)
    assert GestureModel.load(path).taught.names == [] and pipe.model.taught.names == []
    assert desk.status()["taught"] == [] and GestureModel.load(path).revision == 2
    # undo: the file and the pipeline's model are back to revision 1
    desk.undo()
    n = _run(desk, pipe, 1, n)
    assert GestureModel.load(path).taught.names == ["swipe_up"] and pipe.model.taught.names == ["swipe_up"]
    assert pipe.recognizer.model is pipe.model
    assert desk.status()["taught"] == [("swipe_up", "sit", 3)]
    desk.undo()  # only one step of undo: a clear message, no crash
    n = _run(desk, pipe, 1, n)
    assert desk.status()["phase"] == "failed" and "nothing to undo" in desk.status()["message"]
    desk.forget("never_taught")
    _run(desk, pipe, 1, n)
    assert desk.status()["phase"] == "failed" and "never_taught" in desk.status()["message"]


def test_teach_desk_cancel_teaches_nothing_and_recognition_resumes(shipped_model, tmp_path):
    sent = []
    desk, pipe, path = _desk_pipeline(shipped_model, tmp_path, ["static"] + ["swipe_right", "static"] * 6, sent)
    for bad in (("", "bow"), ("x", ""), ("two words", "bow")):
        with pytest.raises(ValueError):
            desk.start(*bad, 3)
    desk.start("anything", "bow", 5)
    n = _run(desk, pipe, 60)
    assert desk.status()["phase"] in ("ready", "show")
    desk.cancel()
    n = _run(desk, pipe, 1, n)
    assert desk.status()["phase"] == "failed" and "cancelled" in desk.status()["message"]
    assert sent == [] and GestureModel.load(path).taught.names == []
    _run(desk, pipe, 300, n)
    assert "walk" in sent, "after the session, gestures are recognised and sent again"
