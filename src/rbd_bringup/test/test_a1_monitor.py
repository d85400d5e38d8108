"""rbd_bringup.a1_monitor: HighCmd packets over real LCM (UDP multicast, ttl=0) become speed samples."""

import socket

import lcm
import pytest

from rbd_bringup.a1_monitor import HighCmdMonitor, command_speed, command_velocity, stop_delay
from rbd_sim import unitree_wire as wire
from rbd_testkit import wait_for
from rbd_wire_oracle import unitree as vendor

WALK, STAND = vendor.MODE_VELOCITY_WALK, vendor.MODE_FORCE_STAND


def free_udp_port():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def high_cmd(mode, vx=0.0, vy=0.0, wz=0.0):
    """HighCmd bytes assembled from the vendor's offsets."""
    return vendor.pack(vendor.HIGH_CMD, {"mode": mode, "gaitType": vendor.GAIT_TROT, "velocity": (vx, vy),
                                         "yawSpeed": wz})


@pytest.fixture
def url():
    return "udpm://239.255.76.67:%d?ttl=0" % free_udp_port()


def test_command_speed_only_counts_walking():
    def speed(*args):
        return command_speed(wire.decode_high_cmd(high_cmd(*args)))

    assert speed(WALK, 0.3, 0.4) == pytest.approx(0.5)
    assert speed(WALK, 0.0, 0.0, -0.7) == pytest.approx(0.7)
    assert speed(STAND, 0.3, 0.0, 0.5) == 0.0


def test_command_velocity_keeps_the_direction_only_when_walking():
    def velocity(*args):
        return command_velocity(wire.decode_high_cmd(high_cmd(*args)))

    assert velocity(WALK, -0.01, -0.12, 0.0) == pytest.approx((-0.01, -0.12, 0.0))
    assert velocity(WALK, 0.0, 0.0, 0.4) == pytest.approx((0.0, 0.0, 0.4))
    assert velocity(STAND, 0.3, 0.2, 0.5) == (0.0, 0.0, 0.0)


def test_monitor_records_packets_over_lcm(url):
    mon = HighCmdMonitor(url)
    pub = lcm.LCM(url)
    try:
        sent = [high_cmd(WALK, 0.3), high_cmd(WALK), high_cmd(STAND, 0.3)]

        def delivered():
            for cmd in sent:
                pub.publish("LCM_High_Cmd", cmd)
            pub.publish("LCM_High_Cmd", b"\x00" * 7)  # garbage: counted, ignored
            pub.publish("OTHER_CHANNEL", sent[0])  # other channels are not commands
            return len(mon.snapshot()) >= 3 and mon.bad >= 1

        # (sent again each step until the monitor has them: the step gives LCM time to deliver)
        assert wait_for(delivered, 5.0, 0.05)
        speeds = [v for _t, v in mon.snapshot()[:3]]
        assert speeds == pytest.approx([0.3, 0.0, 0.0])
        assert all(v in (0.0, pytest.approx(0.3)) for _t, v in mon.snapshot())
    finally:
        mon.close()
    assert not mon._thread.is_alive()


def test_monitor_custom_sink_and_clock(url):
    got = []
    directions = []
    mon = HighCmdMonitor(url, record=lambda t, v: got.append((t, v)), clock=lambda: 42.0,
                         record_velocity=lambda t, v: directions.append((t, v)))
    pub = lcm.LCM(url)
    try:
        assert wait_for(lambda: pub.publish("LCM_High_Cmd", high_cmd(WALK, 0.0, -0.1)) or got, 5.0)
    finally:
        mon.close()
    assert got[0] == (42.0, pytest.approx(0.1)) and mon.snapshot() == []
    assert directions[0] == (42.0, pytest.approx((0.0, -0.1, 0.0)))


def test_stop_delay():
    s = [(0.0, 0.3), (0.1, 0.3), (0.2, 0.0), (0.3, 0.0), (0.4, 0.0)]
    assert stop_delay(s, 0.0, 1.0, 1e-6) == pytest.approx(0.2)
    assert stop_delay(s, 0.25, 1.0, 1e-6) == 0.0  # already still at t0
    assert stop_delay(s + [(0.5, 0.2)], 0.0, 1.0, 1e-6) is None  # moving again: not stopped
    assert stop_delay(s, 2.0, 3.0, 1e-6) is None  # no samples
    assert stop_delay([(0.0, 0.3), (0.1, 0.0), (0.2, 0.3), (0.3, 0.0)], 0.0, 1.0, 1e-6) == pytest.approx(0.3)
