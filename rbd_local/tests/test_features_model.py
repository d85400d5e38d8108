import numpy as np
import pytest

from rbd_local.gestures import features, synthetic
from rbd_local.gestures.model import NONE, GestureModel, train
from rbd_local.gestures.recognizer import GestureRecognizer


def _window(kind, seed=0):
    return synthetic.generate(kind, np.random.default_rng(seed))


def test_features_ignore_position_and_size_of_the_hand():
    w = _window("circle")
    f = features.window_features(w)
    moved = w.copy()
    moved[:, :, :2] = moved[:, :, :2] * 1.7 + np.array([55.0, -20.0])
    moved[:, :, 2] *= 1.7
    np.testing.assert_allclose(features.window_features(moved), f, atol=1e-9)
    assert f.shape == (features.NUM_FEATURES,) == (len(features.feature_names()),)


def test_features_see_the_direction_of_motion():
    right = features.window_features(_window("swipe_right"))
    down = features.window_features(_window("push_down"))
    names = features.feature_names()
    dx, dy = names.index("dx"), names.index("dy")
    assert right[dx] > 1.5 and abs(right[dy]) < right[dx]
    assert down[dy] > 1.0 and abs(down[dx]) < down[dy]


@pytest.mark.parametrize(
    "bad",
    [np.zeros((24, 20, 3)), np.zeros((3, 21, 3)), np.full((24, 21, 3), np.nan), np.zeros((24, 21, 3))],
    ids=["20 points", "3 frames", "nan", "zero-size hand"],
)
def test_bad_windows_raise_value_error(bad):
    with pytest.raises(ValueError):
        features.window_features(bad)


def test_palm_path_smoother_keeps_steady_motion_and_damps_frame_jitter():
    n = synthetic.DEFAULT_SAMPLES
    s = features.smoother(n, 1.0)
    line = np.stack([np.linspace(0.0, 3.0, n), np.linspace(1.0, -2.0, n)], axis=1)
    np.testing.assert_allclose(s @ line, line, atol=1e-9)  # a steady motion, ends included, is not pulled in
    noise = np.random.default_rng(1).normal(0.0, 1.0, (n, 4000))
    assert np.std((s @ noise)[3:-3]) < 0.6 and np.std((s @ noise)[[0, -1]]) < 1.0  # and never amplified
    np.testing.assert_allclose(features.smoother(n, 0.0), np.eye(n))


def test_features_tolerate_a_shaking_camera(shipped_model):
    # a camera that shakes moves all 21 key points together by a few pixels each frame
    rng = np.random.default_rng(11)
    ok = total = 0
    for kind in ("swipe_right", "push_down", "circle"):
        for _ in range(20):
            w = synthetic.generate(kind, rng)
            size = features.hand_size(w[0])
            w[:, :, :2] += rng.normal(0.0, 0.1 * size, (len(w), 1, 2))
            ok += shipped_model.decide(shipped_model.predict_proba(w))[0] == kind
            total += 1
    assert ok >= 0.9 * total, "%d of %d shaky windows recognised" % (ok, total)


def test_resample_is_linear_in_time():
    times = np.array([0.0, 0.1, 0.3])
    frames = np.zeros((3, 21, 3))
    frames[:, :, 0] = np.array([0.0, 1.0, 3.0])[:, None]
    out = features.resample(times, frames, 4)
    np.testing.assert_allclose(out[:, 0, 0], [0.0, 1.0, 2.0, 3.0])


def _tiny_model(threshold=0.8):
    w, y, _ = synthetic.dataset(5, 40, 20)
    return train(features.batch_features(w), y, synthetic.DEFAULT_SAMPLES, 1.2, threshold)


def test_model_roundtrip_and_format_checks(tmp_path):
    m = _tiny_model()
    path = str(tmp_path / "m.npz")
    m.save(path)
    m2 = GestureModel.load(path)
    x = features.batch_features(synthetic.dataset(9, 3, 1)[0])
    np.testing.assert_allclose(m2.predict_proba_features(x), m.predict_proba_features(x))
    assert m2.classes == m.classes and m2.threshold == 0.8

    data = dict(np.load(path))
    data["version"] = np.array(99)
    np.savez(str(tmp_path / "v99.npz"), **data)
    with pytest.raises(ValueError, match="version 99"):
        GestureModel.load(str(tmp_path / "v99.npz"))
    np.savez(str(tmp_path / "other.npz"), a=np.zeros(3))
    with pytest.raises(ValueError, match="not a gesture model"):
        GestureModel.load(str(tmp_path / "other.npz"))
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(ValueError):
        GestureModel.load(str(tmp_path / "junk.npz"))


def test_model_rejects_inconsistent_parameters():
    m = _tiny_model()
    with pytest.raises(ValueError):
        GestureModel(m.classes, m.coef[:, :-1], m.intercept, m.mean, m.scale, 24, 1.2, 0.8)
    with pytest.raises(ValueError):
        GestureModel([c for c in m.classes if c != NONE] + ["x"], m.coef, m.intercept, m.mean, m.scale, 24, 1.2, 0.8)
    with pytest.raises(ValueError):
        GestureModel(m.classes, m.coef, m.intercept, m.mean, m.scale, 24, 1.2, 1.5)


def test_threshold_and_none_class_mean_nothing_is_sent(shipped_model):
    m = shipped_model
    classes = m.classes
    p = np.full(len(classes), 0.21 / (len(classes) - 1))
    p[classes.index("wave")] = 0.79
    assert m.decide(p, 0.8)[0] == NONE  # confident-looking but below threshold
    assert m.decide(p, 0.5)[0] == "wave"
    q = np.zeros(len(classes))
    q[classes.index(NONE)] = 1.0
    assert m.decide(q, 0.1) == (NONE, 1.0)


def test_shipped_model_on_held_out_synthetic_windows(shipped_model):
    m = shipped_model
    assert m.threshold == pytest.approx(0.8)
    assert "synthetic" in m.provenance
    wg, yg, _ = synthetic.dataset(4242, 40, 0)
    wr, _, _ = synthetic.dataset(4243, 0, 100, kinds=synthetic.RANDOM_KINDS)
    dec_g = [m.decide(p)[0] for p in m.predict_proba_features(features.batch_features(wg))]
    dec_r = [m.decide(p)[0] for p in m.predict_proba_features(features.batch_features(wr))]
    assert np.mean(np.array(dec_g) == yg) >= 0.95
    assert np.mean(np.array(dec_r) != NONE) <= 0.03


def test_shipped_model_is_reproducible_from_its_command(shipped_model):
    # Same data and fit as `rbd-train --synthetic --seed 0 --C 30` (the command in the README).
    from rbd_local.train import DEFAULT_C, DEFAULT_THRESHOLD, DEFAULT_WINDOW_S

    w, y, _ = synthetic.dataset(0, 600, 300)
    m = train(features.batch_features(w), y, synthetic.DEFAULT_SAMPLES, DEFAULT_WINDOW_S, DEFAULT_THRESHOLD,
              DEFAULT_C)
    assert m.classes == shipped_model.classes
    np.testing.assert_allclose(m.coef, shipped_model.coef, rtol=1e-4, atol=1e-6)
    np.testing.assert_allclose(m.intercept, shipped_model.intercept, rtol=1e-4, atol=1e-6)


def _stream(kinds, seed, fps=30.0):
    return synthetic.stream(kinds, seed, fps)


def test_recognizer_fires_once_per_gesture_and_honours_cooldown(shipped_model):
    rec = GestureRecognizer(shipped_model, cooldown_s=1.5)
    fired = []
    for t, kp in _stream(["static", "swipe_right", "static", "static"], seed=3):
        d = rec.update(t, kp)
        if d.fired:
            fired.append((t, d.label))
    assert [label for _, label in fired] == ["swipe_right"], fired


def test_recognizer_never_fires_on_a_still_or_missing_hand(shipped_model):
    rec = GestureRecognizer(shipped_model)
    for t, kp in _stream(["static"] * 4, seed=4):
        assert not rec.update(t, kp).fired
    for i in range(100):
        assert not rec.update(10 + i / 30.0, None).fired


def test_recognizer_needs_the_whole_gesture_without_gaps(shipped_model):
    rec = GestureRecognizer(shipped_model, max_gap_s=0.25)
    stream = _stream(["swipe_right"], seed=3)
    decisions = []
    for i, (t, kp) in enumerate(stream):
        # the hand vanishes for 0.4 s in the middle: the window restarts, no full swipe is seen
        decisions.append(rec.update(t, None if 15 <= i < 27 else kp))
    assert not any(d.fired for d in decisions)


def test_recognizer_rejects_bad_arguments(shipped_model):
    with pytest.raises(ValueError):
        GestureRecognizer(shipped_model, threshold=0.0)
    with pytest.raises(ValueError):
        GestureRecognizer(shipped_model, min_consecutive=0)


@pytest.mark.parametrize("gesture", synthetic.GESTURES)
def test_each_gesture_in_a_continuous_stream_fires_itself(shipped_model, gesture):
    for seed in (1, 2, 3):
        rec = GestureRecognizer(shipped_model)
        fired = [d.label for t, kp in _stream(["static", gesture, "static", "static"], seed)
                 for d in [rec.update(t, kp)] if d.fired]
        assert fired[:1] == [gesture], (seed, fired)


def test_cooldown_suppresses_repeats_of_a_continuing_gesture(shipped_model):
    def fired(cooldown):
        rec = GestureRecognizer(shipped_model, cooldown_s=cooldown)
        return [d.label for t, kp in _stream(["static", "wave", "wave", "wave"], 1)
                for d in [rec.update(t, kp)] if d.fired]

    assert fired(0.0) == ["wave"] * 3  # one per window of waving without a cooldown
    assert fired(10.0) == ["wave"]
