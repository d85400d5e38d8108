"""The driver's safety gate: timeouts, clamps, NaN, e-stop, stale state, modes, body pose."""

import math

import pytest

from rbd_a1_driver import unitree_layout as ul
from rbd_a1_driver.safety_gate import GateConfig, SafetyGate


def gate(**kw):
    g = SafetyGate(GateConfig(**kw))
    g.note_state(0.0)
    return g


def moving(out):
    return out.velocity != (0.0, 0.0) or out.yaw_speed != 0.0


def test_fresh_velocity_walks_in_trot():
    g = gate()
    assert g.set_velocity(0.3, 0.1, 0.2, 0.0) == ""
    out = g.command(0.1)
    assert out.mode == ul.MODE_VELOCITY_WALK and out.gait_type == ul.GAIT_TROT
    assert out.velocity == (0.3, 0.1) and out.yaw_speed == 0.2 and out.reason == ""


def test_no_command_for_cmd_timeout_gives_zero():
    g = gate()
    g.set_velocity(0.3, 0.0, 0.0, 0.0)
    g.note_state(0.2)
    assert moving(g.command(0.24))
    out = g.command(0.26)
    assert not moving(out) and "stale" in out.reason


def test_no_command_ever_is_zero():
    out = gate().command(5.0)
    assert not moving(out) and out.mode == ul.MODE_FORCE_STAND


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf")])
def test_non_finite_rejected_and_zeroed(bad):
    g = gate()
    g.set_velocity(0.3, 0.0, 0.0, 0.0)
    assert "non-finite" in g.set_velocity(bad, 0.0, 0.0, 0.05)
    assert not moving(g.command(0.06))
    assert g.rejected == 1
    assert "non-finite" in g.set_velocity(0.1, 0.0, 0.0, 0.07, others=(0.0, bad, 0.0))
    assert not moving(g.command(0.08))


def test_clamped_to_limits():
    g = gate(max_vx=0.4, max_vy=0.2, max_wz=0.5)
    assert "clamped" in g.set_velocity(2.0, -3.0, 9.0, 0.0)
    out = g.command(0.0)
    assert out.velocity == (0.4, -0.2) and out.yaw_speed == 0.5


def test_estop_gate_contract():
    g = gate()
    g.set_velocity(0.3, 0.0, 0.0, 0.0)
    assert moving(g.command(0.01))  # never received => no gate
    g.set_estop(True, 0.02)
    assert not moving(g.command(0.03))
    assert "e-stop" in g.set_velocity(0.3, 0.0, 0.0, 0.04)
    g.note_state(0.05)
    assert not moving(g.command(0.05))
    g.set_estop(False, 0.06)
    assert not moving(g.command(0.07))  # the old command is forgotten
    g.set_velocity(0.2, 0.0, 0.0, 0.08)
    assert moving(g.command(0.09))


def test_stale_state_gives_zero():
    g = gate()
    g.set_velocity(0.3, 0.0, 0.0, 0.0)
    g.set_velocity(0.3, 0.0, 0.0, 0.45)
    assert moving(g.command(0.45))
    g.set_velocity(0.3, 0.0, 0.0, 0.55)
    out = g.command(0.55)
    assert not moving(out) and "HighState" in out.reason
    g2 = SafetyGate()
    g2.set_velocity(0.3, 0.0, 0.0, 0.0)
    assert not moving(g2.command(0.0))  # never had a state


def test_stand_after_delay_with_body_pose():
    g = gate(stand_delay=0.5)
    assert g.set_body_pose(0.2, -0.1, 0.0, -0.05) == ""
    g.set_velocity(0.3, 0.0, 0.0, 0.0)
    out = g.command(0.0)
    assert out.mode == ul.MODE_VELOCITY_WALK and out.euler == (0.0, 0.0, 0.0)
    g.set_velocity(0.0, 0.0, 0.0, 0.1)
    g.note_state(0.3)
    assert g.command(0.3).mode == ul.MODE_VELOCITY_WALK  # settling in place
    g.note_state(0.6)
    out = g.command(0.6)
    assert out.mode == ul.MODE_FORCE_STAND and out.euler == pytest.approx((0.2, -0.1, 0.0))
    assert out.body_height == pytest.approx(-0.05) and not moving(out)
    hc = ul.decode_high_cmd(out.to_high_cmd().pack())
    assert hc.mode == 1 and hc.euler == pytest.approx((0.2, -0.1, 0.0))


@pytest.mark.parametrize(
    "pose",
    [(math.nan, 0, 0, 0), (0, 0, 0, math.inf), (0.9, 0, 0, 0), (0, -0.8, 0, 0), (0, 0, 0.7, 0), (0, 0, 0, -0.2),
     (0, 0, 0, 0.1)],
)
def test_bad_body_pose_rejected(pose):
    g = gate()
    assert g.set_body_pose(*pose) != ""
    assert g.command(1.0).euler == (0.0, 0.0, 0.0)


def test_body_pose_rejected_during_estop():
    g = gate()
    g.set_estop(True, 0.0)
    assert "e-stop" in g.set_body_pose(0.2, 0.0, 0.0, 0.0)


def test_config_validation():
    with pytest.raises(ValueError):
        GateConfig(max_vx=float("nan"))
    with pytest.raises(ValueError):
        GateConfig(cmd_timeout=0.0)
    with pytest.raises(ValueError):
        GateConfig(min_body_height=0.1)


def periodic_estop(g, value, t0, t1, period=0.1):
    """Feed e-stop messages every period from t0 to t1 (inclusive); returns the last time."""
    t = t0
    while t <= t1 + 1e-9:
        g.set_estop(value, t)
        g.note_state(t)
        last = t
        t += period
    return last


def test_estop_signal_lost_engages_after_timeout():
    g = gate(estop_timeout=0.5)
    last = periodic_estop(g, False, 0.0, 1.0)
    assert g.estop_armed and not g.estop
    g.set_velocity(0.3, 0.0, 0.0, last)
    g.note_state(last + 0.45)
    g.set_velocity(0.3, 0.0, 0.0, last + 0.45)
    assert moving(g.command(last + 0.49))  # within the timeout: still walking
    out = g.command(last + 0.51)
    assert not moving(out) and "signal lost" in out.reason
    assert g.estop and g.estop_lost
    # cmd_vel keeps coming: ignored; body poses too
    assert "e-stop" in g.set_velocity(0.3, 0.0, 0.0, last + 0.6)
    assert "e-stop" in g.set_body_pose(0.0, 0.0, 0.0, 0.0)
    g.note_state(last + 0.7)
    assert not moving(g.command(last + 0.7))


def test_estop_signal_lost_detected_by_set_velocity_alone():
    g = gate(estop_timeout=0.5)
    last = periodic_estop(g, False, 0.0, 0.3)
    g.note_state(last + 0.6)
    assert "e-stop" in g.set_velocity(0.3, 0.0, 0.0, last + 0.6)
    assert not moving(g.command(last + 0.6))


def test_estop_signal_lost_released_only_by_fresh_false():
    g = gate(estop_timeout=0.5)
    last = periodic_estop(g, False, 0.0, 0.5)
    assert not moving(g.command(last + 0.6)) and g.estop_lost
    g.set_estop(True, last + 0.7)  # the respawned controller: EMERGENCY_STOP
    assert g.estop and not g.estop_lost
    periodic_estop(g, True, last + 0.8, last + 1.5)
    g.set_velocity(0.3, 0.0, 0.0, last + 1.5)
    assert not moving(g.command(last + 1.5))
    g.set_estop(False, last + 1.6)  # release
    assert not g.estop
    assert not moving(g.command(last + 1.61))  # the old command is forgotten
    g.set_velocity(0.3, 0.0, 0.0, last + 1.62)
    assert moving(g.command(last + 1.63))


def test_estop_true_signal_lost_stays_engaged():
    g = gate(estop_timeout=0.5)
    last = periodic_estop(g, True, 0.0, 0.5)
    g.command(last + 2.0)
    assert g.estop and g.estop_lost
    assert "e-stop" in g.set_velocity(0.3, 0.0, 0.0, last + 2.1)


def test_one_shot_estop_publisher_never_arms_the_watchdog():
    """A latched one-shot publisher (isolated tests, rostopic pub -1) keeps the old contract."""
    g = gate(estop_timeout=0.5)
    g.set_estop(True, 0.0)
    g.set_estop(False, 1.0)  # 1 s apart: not periodic
    assert not g.estop_armed
    g.note_state(5.0)
    g.set_velocity(0.3, 0.0, 0.0, 5.0)
    assert moving(g.command(5.0))


def test_estop_never_received_is_no_gate_even_with_timeout():
    g = gate(estop_timeout=0.5)
    g.note_state(10.0)
    g.set_velocity(0.3, 0.0, 0.0, 10.0)
    assert moving(g.command(10.0)) and not g.estop_armed


def test_estop_timeout_zero_disables_the_watchdog():
    g = gate(estop_timeout=0.0)
    last = periodic_estop(g, False, 0.0, 1.0)
    assert not g.estop_armed
    g.note_state(last + 5.0)
    g.set_velocity(0.3, 0.0, 0.0, last + 5.0)
    assert moving(g.command(last + 5.0))


@pytest.mark.parametrize("bad", [-0.1, float("nan"), "x"])
def test_bad_estop_timeout_rejected(bad):
    with pytest.raises(ValueError):
        GateConfig(estop_timeout=bad)


def test_estop_required_holds_until_the_first_estop_message():
    g = gate(estop_required=True)
    assert g.estop_missing and not g.estop
    assert "estop_required" in g.set_velocity(0.3, 0.0, 0.0, 0.0)
    out = g.command(0.1)
    assert not moving(out) and "estop_required" in out.reason
    assert "estop_required" in g.set_body_pose(0.1, 0.0, 0.0, 0.0)
    g.set_estop(False, 0.2)
    assert not g.estop_missing
    assert g.set_velocity(0.3, 0.0, 0.0, 0.2) == ""
    assert moving(g.command(0.25))
    assert g.set_body_pose(0.1, 0.0, 0.0, 0.0) == ""


def test_estop_required_first_message_true_stays_engaged():
    g = gate(estop_required=True)
    g.set_estop(True, 0.0)
    assert not g.estop_missing and g.estop
    assert "e-stop engaged" in g.set_velocity(0.3, 0.0, 0.0, 0.1)
    assert not moving(g.command(0.1))


@pytest.mark.parametrize("bad", [1, "true", None])
def test_estop_required_must_be_a_bool(bad):
    with pytest.raises(ValueError):
        GateConfig(estop_required=bad)


def walking_gate():
    g = gate()
    g.set_estop(False, 0.0)
    g.set_velocity(0.3, 0.0, 0.0, 0.0)
    assert moving(g.command(0.01))
    return g


def test_remote_estop_engages_in_the_next_command_and_forgets_the_velocity():
    g = walking_gate()
    assert g.remote_state == "ready"
    assert g.set_remote(True) is True
    out = g.command(0.02)
    assert not moving(out) and "remote" in out.reason and g.remote_state == "engaged"
    assert g.set_remote(True) is False  # already latched
    assert "remote e-stop" in g.set_velocity(0.3, 0.0, 0.0, 0.03)
    assert not moving(g.command(0.04))
    assert "e-stop" in g.set_body_pose(0.1, 0.0, 0.0, 0.0)


def test_remote_estop_released_only_by_the_operator_after_the_controller_engaged():
    g = walking_gate()
    g.set_remote(True)
    g.set_remote(False)  # let go: still engaged
    g.set_estop(False, 0.05)  # the controller's periodic false, before it engaged: no release
    assert g.remote_state == "engaged"
    g.set_estop(True, 0.1)  # the controller engaged (told by the driver)
    assert g.remote_state == "engaged"
    g.set_estop(False, 0.2)  # the operator releases
    assert g.remote_state == "ready"
    assert not moving(g.command(0.21))  # the old command is forgotten
    g.set_velocity(0.3, 0.0, 0.0, 0.22)
    assert moving(g.command(0.23))


def test_remote_estop_release_while_held_is_void():
    g = walking_gate()
    g.set_remote(True)
    g.set_estop(True, 0.1)
    g.set_estop(False, 0.2)  # released while the combination is still held
    assert g.remote_state == "engaged"
    g.set_remote(False)
    g.set_estop(False, 0.3)  # a further false (periodic republish) does not release either
    assert g.remote_state == "engaged"
    g.set_velocity(0.3, 0.0, 0.0, 0.31)
    assert not moving(g.command(0.32))
    g.set_estop(True, 0.4)  # engaged again, then released with the buttons up
    g.set_estop(False, 0.5)
    assert g.remote_state == "ready"


def test_remote_estop_off():
    g = gate(remote_estop=False)
    g.set_velocity(0.3, 0.0, 0.0, 0.0)
    assert g.set_remote(True) is False
    assert g.remote_state == "off" and not g.remote_held and moving(g.command(0.01))


@pytest.mark.parametrize("bad", ["true", 1, None])
def test_remote_estop_must_be_a_bool(bad):
    with pytest.raises(ValueError, match="remote_estop"):
        GateConfig(remote_estop=bad)
