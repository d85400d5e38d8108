"""IMU and ZED2 noise models: gravity convention, bias, seeded determinism, drift/jump statistics."""

import math

import numpy as np
import pytest

from rbd_geometry.rotation import rpy_to_matrix
from rbd_sim.imu import STANDARD_GRAVITY, AccelerationEstimator, ImuModel
from rbd_sim.zed2 import Zed2Model, in_tracking_frame


def test_level_imu_reads_plus_one_g_on_z():
    imu = ImuModel(seed=1)
    acc = np.array([imu.sample(0.01, np.eye(3), np.zeros(3), np.zeros(3))[0] for _ in range(2000)])
    assert acc[:, 2].mean() == pytest.approx(STANDARD_GRAVITY, abs=0.2)
    assert np.abs(acc[:, :2].mean(axis=0)).max() < 0.2
    assert 0.02 < acc[:, 2].std() < 0.05  # accel noise 0.03 m/s^2


def test_imu_without_noise_is_exact_specific_force():
    imu = ImuModel(0, 0, 0, 0, 0, 0, seed=1)
    # Pitched 90 deg nose down: x points at the floor, the support force (up) reads along -x.
    a, g = imu.sample(0.01, rpy_to_matrix(0, math.pi / 2, 0), np.array([0.1, 0.2, 0.3]), np.zeros(3))
    np.testing.assert_allclose(a, [-STANDARD_GRAVITY, 0, 0], atol=1e-9)
    np.testing.assert_allclose(g, [0.1, 0.2, 0.3])
    # Accelerating forward at 1 m/s^2 while level.
    a, _ = imu.sample(0.01, np.eye(3), np.zeros(3), np.array([1.0, 0, 0]))
    np.testing.assert_allclose(a, [1.0, 0, STANDARD_GRAVITY], atol=1e-9)


def test_imu_bias_is_seeded_and_persistent():
    a = ImuModel(gyro_bias_walk=0.0, seed=3)
    b = ImuModel(gyro_bias_walk=0.0, seed=3)
    c = ImuModel(gyro_bias_walk=0.0, seed=4)
    assert np.array_equal(a.gyro_bias, b.gyro_bias)
    assert not np.array_equal(a.gyro_bias, c.gyro_bias)
    gyro = np.array([a.sample(0.01, np.eye(3), np.zeros(3), np.zeros(3))[1] for _ in range(5000)])
    # A stationary gyro averages to its bias, not to zero (what made the thesis' EKF drift).
    np.testing.assert_allclose(gyro.mean(axis=0), a.gyro_bias, atol=3e-4)
    assert np.abs(a.gyro_bias).max() > 1e-4


def test_imu_rejects_negative_parameters():
    with pytest.raises(ValueError):
        ImuModel(accel_noise_std=-1)


def test_acceleration_estimator():
    est = AccelerationEstimator(time_constant=0.0)
    for i in range(10):
        a = est.update(i * 0.01, np.array([0.5 * i * 0.01, 0, 0]))
    np.testing.assert_allclose(a, [0.5, 0, 0], atol=1e-9)
    a = est.update(0.05, np.zeros(3))  # out of order: ignored, restarts
    np.testing.assert_allclose(a, [0.5, 0, 0], atol=1e-9)


def run_zed(model, seconds=60.0, rate=15.0, speed=0.0, turn=0.0):
    out = []
    dt = 1.0 / rate
    for k in range(int(seconds * rate)):
        t = k * dt
        est = model.step(dt, (speed * t, 0.0, 0.28), (0.0, 0.0, math.atan2(math.sin(turn * t), math.cos(turn * t))))
        out.append((est.position, est.rpy, est.jumped))
    return out


def test_zed2_same_seed_same_output_different_seed_differs():
    a = run_zed(Zed2Model(seed=11), speed=0.3, turn=0.2)
    b = run_zed(Zed2Model(seed=11), speed=0.3, turn=0.2)
    c = run_zed(Zed2Model(seed=12), speed=0.3, turn=0.2)
    assert a == b
    assert a != c


def test_zed2_all_off_is_exact():
    m = Zed2Model(0, 0, 0, 0, 0, 0, jump_rate=0.0, seed=1)
    for _pos, _rpy, jumped in run_zed(m, seconds=5, speed=0.5, turn=0.3):
        assert not jumped
    est = m.step(0.1, (1.0, 2.0, 0.3), (0.01, 0.02, 0.5))
    assert est.position == pytest.approx((1.0, 2.0, 0.3))
    assert est.rpy == pytest.approx((0.01, 0.02, 0.5))


def test_zed2_drift_grows_with_distance_as_modelled():
    # Walking 0.6 m/s for 30 s = 18 m: random walk std per axis = drift_per_m * sqrt(18 m).
    finals = []
    for seed in range(60):
        m = Zed2Model(noise_pos_std=0.0, drift_per_m=0.03, drift_per_s=0.0, jump_rate=0.0, seed=seed)
        pos = run_zed(m, seconds=30.0, speed=0.6)[-1][0]
        finals.append(pos[1])  # lateral error (true y = 0)
    std = float(np.sqrt(np.mean(np.square(finals))))
    assert std == pytest.approx(0.03 * math.sqrt(18.0), rel=0.3)
    standing = []
    for s in range(5):
        m = Zed2Model(noise_pos_std=0.0, drift_per_m=0.03, drift_per_s=0.0, jump_rate=0.0, seed=s)
        standing.append(run_zed(m, seconds=10.0)[-1][0][1])
    assert max(abs(v) for v in standing) < 1e-12  # no motion, no time drift: no drift


def test_zed2_jump_statistics():
    rate, seconds, runs = 0.1, 40.0, 60
    counts = []
    sizes = []
    for seed in range(runs):
        m = Zed2Model(
            noise_pos_std=0.0,
            drift_per_m=0.0,
            drift_per_s=0.0,
            yaw_drift_per_s=0.0,
            jump_rate=rate,
            jump_reset_prob=0.0,
            jump_min=0.1,
            jump_max=0.3,
            seed=seed,
        )
        prev = None
        for pos, _rpy, jumped in run_zed(m, seconds=seconds):
            if jumped and prev is not None:
                sizes.append(math.hypot(pos[0] - prev[0], pos[1] - prev[1]))
            prev = pos
        counts.append(m.jumps)
    mean = float(np.mean(counts))
    assert mean == pytest.approx(rate * seconds, rel=0.2)  # Poisson mean 4 per run, 240 in all
    assert min(sizes) >= 0.1 - 1e-9 and max(sizes) <= 0.3 + 1e-9


def test_zed2_reset_jump_removes_drift():
    m = Zed2Model(noise_pos_std=0.0, drift_per_m=0.1, drift_per_s=0.0, jump_rate=1000.0, jump_reset_prob=1.0, seed=5)
    m.step(0.1, (0.0, 0.0, 0.0), (0, 0, 0))
    est = m.step(0.1, (1.0, 0.0, 0.0), (0, 0, 0))  # moved 1 m, then a certain relocalisation
    assert est.jumped
    assert est.position == pytest.approx((1.0, 0.0, 0.0))
    assert est.covariance[0] < 1e-4


def test_zed2_covariance_grows_until_reset():
    m = Zed2Model(jump_rate=0.0, seed=1)
    c0 = m.step(0.07, (0, 0, 0.28), (0, 0, 0)).covariance[0]
    for k in range(1, 100):
        c = m.step(0.07, (0.05 * k, 0, 0.28), (0, 0, 0)).covariance
    assert c[0] > c0 and c[7] == c[0]
    assert len(c) == 36


def test_zed2_rejects_bad_parameters():
    with pytest.raises(ValueError):
        Zed2Model(jump_min=0.5, jump_max=0.1)
    with pytest.raises(ValueError):
        Zed2Model(jump_reset_prob=2.0)


def test_zed2_tracking_frame_starts_at_the_robots_start_pose():
    # Placed at (2, -1) facing 40 deg, the ZED2 reports zero there, as a real one switched on there.
    origin = (2.0, -1.0, math.radians(40.0))
    pos, rpy = in_tracking_frame((2.0, -1.0, 0.28), (0.01, -0.02, math.radians(40.0)), origin)
    assert pos == pytest.approx((0.0, 0.0, 0.28), abs=1e-12)
    assert rpy == pytest.approx((0.01, -0.02, 0.0), abs=1e-12)
    # One metre along the start heading is (1, 0) in the tracking frame; a quarter turn left is +90 deg.
    c, s = math.cos(origin[2]), math.sin(origin[2])
    pos, rpy = in_tracking_frame((2.0 + c, -1.0 + s, 0.28), (0.0, 0.0, origin[2] + math.pi / 2), origin)
    assert pos == pytest.approx((1.0, 0.0, 0.28), abs=1e-12)
    assert rpy[2] == pytest.approx(math.pi / 2, abs=1e-12)
    # The origin at zero changes nothing (the default).
    assert in_tracking_frame((1.5, 0.5, 0.3), (0.0, 0.0, 3.0), (0.0, 0.0, 0.0)) == ((1.5, 0.5, 0.3), (0.0, 0.0, 3.0))
