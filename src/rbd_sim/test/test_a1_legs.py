"""The mock A1's legs: a1_description angle conventions, standing / lying / trotting, foot forces."""

import math

import pytest

from rbd_sim.a1_legs import MASS, TROT_PERIOD, Legs, leg_fk, leg_ik

WEIGHT = MASS * 9.81


def legs_at(body_height, walking=False, velocity=(0.0, 0.0, 0.0), t_end=0.0, dt=0.004):
    legs = Legs()
    t = 0.0
    legs.update(t, walking, body_height, velocity)
    while t < t_end:
        t += dt
        legs.update(t, walking, body_height, velocity)
    return legs


def test_ik_inverts_fk():
    for x, z in ((0.0, -0.28), (0.08, -0.25), (-0.1, -0.2), (0.0, -0.12)):
        assert leg_fk(*leg_ik(x, z)) == pytest.approx((x, z), abs=1e-9)


def test_standing_angles_are_the_a1s():
    legs = legs_at(0.28)
    for leg in range(4):
        hip, thigh, calf = legs.q[3 * leg: 3 * leg + 3]
        assert hip == pytest.approx(0.0)
        assert 0.7 <= thigh <= 0.9 and -1.6 <= calf <= -1.4
    assert legs.force == pytest.approx([WEIGHT / 4] * 4)
    assert legs.tau[2] > 0.0  # the calf holds the load (a1_description sign)


def test_lying_angles_at_minimum_body_height():
    legs = legs_at(0.12)
    thigh, calf = legs.q[1], legs.q[2]
    assert thigh == pytest.approx(math.acos(0.12 / 0.4), abs=1e-6)
    assert calf == pytest.approx(-2 * math.acos(0.12 / 0.4), abs=1e-6)
    assert calf > -2.7  # within the A1's calf limit (a1_const.h)


def test_trot_alternates_diagonal_pairs():
    samples = []
    legs = Legs()
    t = 0.0
    while t < 2 * TROT_PERIOD:
        legs.update(t, True, 0.28, (0.3, 0.0, 0.0))
        samples.append((list(legs.force), list(legs.q)))
        t += 0.01
    for force, _ in samples:
        assert force[0] == force[3] and force[1] == force[2]  # FR with RL, FL with RR
        assert sum(force) == pytest.approx(WEIGHT)  # two stance feet carry the robot
    fr_loaded = [f[0] > 0 for f, _ in samples]
    assert 0.4 < sum(fr_loaded) / len(fr_loaded) < 0.6  # half the time in stance
    thighs = [q[1] for _, q in samples]
    assert max(thighs) - min(thighs) > 0.1  # the legs swing
    assert all(0.3 < th < 1.3 for th in thighs)


def test_joint_rates_follow_the_angles():
    legs = legs_at(0.28, walking=True, velocity=(0.3, 0.0, 0.0), t_end=0.1)
    q0 = list(legs.q)
    legs.update(0.1 + 0.004 + 1e-9, True, 0.28, (0.3, 0.0, 0.0))
    for a, b, rate in zip(q0, legs.q, legs.dq):
        assert rate == pytest.approx((b - a) / 0.004, rel=1e-3, abs=1e-6)


def test_sideways_and_turning_swing_the_hips():
    legs = legs_at(0.28, walking=True, velocity=(0.0, 0.2, 0.0), t_end=0.05)
    assert any(abs(legs.q[3 * leg]) > 0.01 for leg in range(4))
    legs = legs_at(0.28, walking=True, velocity=(0.0, 0.0, 0.0), t_end=0.05)
    assert all(abs(legs.q[3 * leg]) < 1e-9 for leg in range(4))  # in place: no sideways swing
