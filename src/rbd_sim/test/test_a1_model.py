"""Mock A1 kinematics: latency, limits, drift, watchdog, body pose, bad packets (fixed time steps)."""

import math

import pytest

from rbd_sim import unitree_wire as wire
from rbd_sim.a1_model import A1Config, A1Model
from rbd_wire_oracle import unitree as vendor

DT = 0.004  # the driver's default 250 Hz
MODE_BACKFLIP = 9


def walk(vx=0.0, vy=0.0, wz=0.0):
    """A HighCmd assembled from the vendor's offsets (the mock must understand it)."""
    return vendor.pack(vendor.HIGH_CMD, {"mode": vendor.MODE_VELOCITY_WALK, "gaitType": vendor.GAIT_TROT,
                                         "velocity": (vx, vy), "yawSpeed": wz})


def stand(roll=0.0, pitch=0.0, yaw=0.0, dh=0.0):
    return vendor.pack(vendor.HIGH_CMD, {"mode": vendor.MODE_FORCE_STAND, "euler": (roll, pitch, yaw),
                                         "bodyHeight": dh})


def state_of(model, layout="3.3.4"):
    """The mock's HighState packet in an SDK layout, read back through the vendor table."""
    return vendor.unpack(vendor.HIGH_STATES[layout], wire.encode_high_state(layout, model.high_state()))


def drive(model, packet_fn, t0, duration, dt=DT):
    """Send packet_fn(t) every dt for duration (None = send nothing), stepping the model."""
    t = t0
    n = int(round(duration / dt))
    for _ in range(n):
        pkt = packet_fn(t)
        if pkt is not None:
            model.receive(pkt, t)
        t += dt
        model.step(t)
    return t


def test_forward_03_for_3s_moves_09():
    m = A1Model(A1Config(seed=3))
    t = drive(m, lambda t: walk(0.3), 0.0, 3.0)
    t = drive(m, lambda t: walk(0.0), t, 1.0)
    assert m.x == pytest.approx(0.9, rel=0.02) and m.rejected == 0
    assert abs(m.y) < 1e-6 and m.vx == 0.0


def test_latency_delays_motion():
    m = A1Model(A1Config(latency=0.08))
    t = drive(m, lambda t: walk(0.3), 0.0, 0.076)
    assert m.x == 0.0 and m.vx == 0.0
    drive(m, lambda t: walk(0.3), t, 0.04)
    assert m.vx > 0.0


def test_velocity_and_acceleration_limits():
    m = A1Model(A1Config(max_vx=0.8, max_acc_x=1.0, latency=0.0))
    drive(m, lambda t: walk(5.0), 0.0, 0.2)
    assert m.vx == pytest.approx(0.2, abs=0.01)  # 1 m/s^2 for 0.2 s
    drive(m, lambda t: walk(5.0), 0.2, 1.0)
    assert m.vx == pytest.approx(0.8)


def turn_180(drift, seed=1, wz=0.5):
    m = A1Model(A1Config(drift_per_180=drift, seed=seed))
    t = drive(m, lambda t: walk(wz=wz), 0.0, math.pi / wz)
    drive(m, lambda t: walk(), t, 1.0)
    return m


def test_turn_180_drifts_04_when_on():
    m = turn_180(0.4)
    assert abs(abs(m.heading) - math.pi) < 0.05
    assert math.hypot(m.x, m.y) == pytest.approx(0.4, abs=0.06)
    # Sideways to the heading the turn started from, towards the turn side (left for CCW).
    assert m.y > 0.34 and abs(m.x) < 0.05
    # The robot's own odometry does not see the slip.
    assert math.hypot(m.odom_x, m.odom_y) < 1e-6


def test_turn_out_and_back_adds_up_sideways():
    m = A1Model(A1Config(drift_per_180=0.4, drift_sigma=0.0))
    t = drive(m, lambda t: walk(wz=0.5), 0.0, math.pi / 0.5)
    t = drive(m, lambda t: walk(), t, 0.5)
    t = drive(m, lambda t: walk(wz=-0.5), t, math.pi / 0.5)
    drive(m, lambda t: walk(), t, 1.0)
    assert abs(m.heading) < 0.05
    assert m.y == pytest.approx(0.8, abs=0.05) and abs(m.x) < 0.05


def test_turn_180_no_drift_when_off():
    m = turn_180(0.0)
    assert math.hypot(m.x, m.y) < 0.02


def test_drift_seeded_and_deterministic():
    a, b, c = turn_180(0.4, seed=5), turn_180(0.4, seed=5), turn_180(0.4, seed=6)
    assert (a.x, a.y) == (b.x, b.y)
    assert (a.x, a.y) != (c.x, c.y)
    assert 0.3 < math.hypot(c.x, c.y) < 0.5


def test_watchdog_stops_stale_commands():
    m = A1Model(A1Config(cmd_timeout=0.1))
    t = drive(m, lambda t: walk(0.3), 0.0, 1.0)
    assert m.vx == pytest.approx(0.3)
    x_stop = m.x
    drive(m, lambda t: None, t, 1.0)
    assert m.vx == 0.0
    # latency 0.05 + watchdog 0.1 + deceleration 0.2 s at 1.5 m/s^2
    assert m.x - x_stop < 0.3 * (0.05 + 0.1 + 0.2) + 0.01


@pytest.mark.parametrize(
    "packet",
    [
        b"",
        b"\x01" * 7,
        b"\x00" * 112,
        walk(0.3) + b"\x00",
        walk(float("nan")),
        walk(0.3, wz=float("inf")),
        walk(0.3)[:10] + bytes([99]) + walk(0.3)[11:],  # unknown mode
        bytes([0xEE]) + walk(0.3)[1:],  # levelFlag of a later SDK
    ],
)
def test_bad_packets_hold_still(packet):
    m = A1Model(A1Config())
    t = 0.0
    for _ in range(200):
        assert m.receive(packet, t) != ""
        t += DT
        m.step(t)
    assert (m.x, m.y, m.heading) == (0.0, 0.0, 0.0) and m.rejected == 200


def test_bad_packet_between_good_ones_is_ignored():
    m = A1Model(A1Config())
    drive(m, lambda t: walk(0.3) if int(t / DT) % 2 else walk(float("nan")), 0.0, 1.0)
    assert m.vx == pytest.approx(0.3) and m.rejected > 100


def test_unmodeled_mode_holds_still():
    packet = vendor.pack(vendor.HIGH_CMD, {"mode": MODE_BACKFLIP, "velocity": (0.5, 0.0)})
    m = A1Model(A1Config())
    drive(m, lambda t: packet, 0.0, 1.0)
    assert m.x == 0.0 and m.unmodeled_mode == MODE_BACKFLIP


def test_force_stand_tilts_and_lowers_body():
    m = A1Model(A1Config())
    drive(m, lambda t: stand(0.3, -0.2, 0.1, -0.16), 0.0, 1.5)
    x, y, z, roll, pitch, yaw = m.pose()
    assert (roll, pitch, yaw) == pytest.approx((0.3, -0.2, 0.1))
    assert z == pytest.approx(0.28 - 0.16)
    for layout in ("3.3", "3.3.4"):
        s = state_of(m, layout)
        assert s["imu"]["rpy"] == pytest.approx((0.3, -0.2, 0.1), abs=1e-6)
        assert s["bodyHeight"] == pytest.approx(0.12)
    # Saturated by the robot.
    drive(m, lambda t: stand(2.0, 0.0, 0.0, -1.0), 1.5, 3.0)
    assert m.pose()[3] == pytest.approx(0.75) and m.pose()[2] == pytest.approx(0.12)


def test_walking_returns_body_to_level():
    m = A1Model(A1Config())
    t = drive(m, lambda t: stand(0.3, 0.0, 0.0, 0.0), 0.0, 1.0)
    drive(m, lambda t: walk(0.1), t, 1.0)
    assert m.pose()[3] == pytest.approx(0.0)


def test_high_state_reports_motion():
    m = A1Model(A1Config(drift_per_180=0.0))
    drive(m, lambda t: walk(0.3, 0.0, 0.2), 0.0, 2.0)
    for layout in ("3.3", "3.3.4"):
        s = state_of(m, layout)
        assert s["levelFlag"] == vendor.HIGHLEVEL and s["mode"] == vendor.MODE_VELOCITY_WALK
        assert s["gaitType"] == vendor.GAIT_TROT
        assert s["velocity"][0] == pytest.approx(0.3) and s["yawSpeed"] == pytest.approx(0.2)
        assert s["imu"]["gyroscope"][2] == pytest.approx(0.2)
        assert s["position"][0] == pytest.approx(m.x, abs=1e-5) and s["position"][1] == pytest.approx(m.y, abs=1e-5)
        assert s["imu"]["rpy"][2] == pytest.approx(m.heading, abs=1e-6)


def test_config_validation():
    with pytest.raises(ValueError):
        A1Config(latency=float("nan"))
    with pytest.raises(ValueError):
        A1Config(max_vx=0.0)
    with pytest.raises(ValueError):
        A1Config(drift_heading=4.0)


def test_start_pose_ground_truth_there_odometry_at_zero():
    # Placed at (1.5, -0.7) facing 40 deg: ground truth starts there, the robot's own odometry and
    # IMU yaw start at zero (as a real A1's, wherever it is switched on), and walking forward moves
    # the truth along the start heading while the odometry counts along its own x.
    yaw0 = math.radians(40.0)
    m = A1Model(A1Config(x0=1.5, y0=-0.7, yaw0=yaw0, drift_per_180=0.0))
    x, y, _z, _r, _p, yaw = m.pose()
    assert (x, y, yaw) == pytest.approx((1.5, -0.7, yaw0), abs=1e-12)
    s = state_of(m)
    assert tuple(s["position"]) == (0.0, 0.0, 0.0)
    assert s["imu"]["rpy"][2] == pytest.approx(0.0, abs=1e-6)
    t = drive(m, lambda t: walk(0.3), 0.0, 2.0)
    drive(m, lambda t: walk(0.0), t, 1.0)
    d = math.hypot(m.x - 1.5, m.y + 0.7)
    assert d == pytest.approx(0.6, rel=0.03)
    assert math.atan2(m.y + 0.7, m.x - 1.5) == pytest.approx(yaw0, abs=1e-6)
    s = state_of(m)
    assert s["position"][0] == pytest.approx(d, rel=1e-3) and abs(s["position"][1]) < 1e-5
