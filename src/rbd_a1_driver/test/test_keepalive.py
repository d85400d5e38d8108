"""The keep-alive process's decisions: silent while the driver sends, repeats its last command when it
stalls, zero velocity after ``hold``; and the process itself over real LCM with the driver's pipe."""

import contextlib
import os
import socket
import subprocess
import sys
import time

import lcm
import pytest

from rbd_a1_driver.keepalive import RECORD, KeepAlive, at_rest, publish_and_record, record, zero_velocity
from rbd_wire_oracle import unitree as vendor

WALK = vendor.pack(vendor.HIGH_CMD, {"mode": 2, "gaitType": 1, "velocity": (0.3, 0.1), "yawSpeed": 0.2})
STAND = vendor.pack(vendor.HIGH_CMD, {"mode": 2, "gaitType": 1})
L2_B = (1 << vendor.BUTTON_BITS["L2"]) | (1 << vendor.BUTTON_BITS["B"])


def test_silent_while_the_driver_sends():
    k = KeepAlive(0.004, 0.010, 0.05)
    assert k.due(0.0) is None and k.wait(0.0) is None
    for i in range(100):
        k.from_driver(WALK, i * 0.004)
        assert k.due(i * 0.004 + 0.009) is None
    assert k.filled == 0


def test_a_stall_right_after_the_publish_does_not_delay_the_first_fill():
    """The record's stamp is the packet's departure, so the first fill comes ``gap`` after it.

    The driver's thread stalls 15 ms right after the publish (a GIL wait under load). Stamped
    after the publish, the keep-alive would count its gap from 15 ms after the packet.
    """
    now = [5.0]
    wire = []

    def publish(packet):
        wire.append((now[0], packet))
        now[0] += 0.015  # the thread does not get back before this

    rec = publish_and_record(publish, WALK, clock=lambda: now[0])
    sent, packet = RECORD.unpack(rec)
    assert packet == WALK and wire == [(5.0, WALK)]
    assert sent == 5.0  # when it left, not when the thread got back
    k = KeepAlive(0.004, 0.010, 0.05)
    k.from_driver(packet, sent)
    assert k.due(5.0 + 0.010) == WALK  # 10 ms after the packet on the wire, not 25


def test_fills_a_stall_with_the_last_command_then_zero_velocity():
    k = KeepAlive(0.004, 0.010, 0.05)
    k.from_driver(WALK, 1.0)
    assert k.due(1.009) is None
    assert k.wait(1.009) == pytest.approx(0.001)
    times = [1.010 + 0.004 * i for i in range(30)]
    sent = [(t, k.due(t)) for t in times]
    assert all(p is not None for _, p in sent)  # one per period while the driver is silent
    for t, p in sent:
        v = vendor.unpack(vendor.HIGH_CMD, p)
        if t - 1.0 <= 0.05:
            assert p == WALK
        else:
            assert v["velocity"] == (0.0, 0.0) and v["yawSpeed"] == 0.0 and v["mode"] == 2
    k.from_driver(WALK, 1.2)  # the driver is back
    assert k.due(1.205) is None


def test_zero_velocity_keeps_the_rest():
    v = vendor.unpack(vendor.HIGH_CMD, zero_velocity(vendor.pack(vendor.HIGH_CMD, {
        "mode": 2, "velocity": (0.3, 0.1), "yawSpeed": 0.2, "bodyHeight": -0.05, "led": [{"r": 9}] * 4})))
    assert v["velocity"] == (0.0, 0.0) and v["yawSpeed"] == 0.0
    assert v["mode"] == 2 and v["bodyHeight"] == pytest.approx(-0.05) and v["led"][3]["r"] == 9


def test_at_rest_reads_velocity_and_yaw_rate():
    assert at_rest(STAND) and not at_rest(WALK)
    assert not at_rest(vendor.pack(vendor.HIGH_CMD, {"mode": 2, "yawSpeed": -0.1}))
    assert not at_rest(vendor.pack(vendor.HIGH_CMD, {"mode": 2, "velocity": (0.0, 0.05)}))


def test_a_remote_press_makes_every_fill_zero_velocity_until_the_driver_stops_itself():
    k = KeepAlive(0.004, 0.010, 0.05, L2_B)
    k.from_driver(WALK, 1.0)
    k.from_state(L2_B | 1 << vendor.BUTTON_BITS["up"], 1.002)  # the press (another button held too)
    fills = [vendor.unpack(vendor.HIGH_CMD, k.due(1.010 + 0.004 * i)) for i in range(10)]  # within hold
    assert all(f["velocity"] == (0.0, 0.0) and f["yawSpeed"] == 0.0 and f["mode"] == 2 for f in fills)
    k.from_driver(WALK, 1.001)  # a late record of a command sent before the press: still latched
    assert at_rest(k.due(1.012))
    k.from_driver(STAND, 1.05)  # the driver, after the press, sends zero velocity: its gate holds
    assert k.remote_since is None
    k.from_driver(WALK, 1.5)  # released by the operator later: the driver walks again
    assert k.due(1.511) == WALK  # and a stall repeats that walk as before


def test_buttons_other_than_the_combination_change_nothing():
    k = KeepAlive(0.004, 0.010, 0.05, L2_B)
    k.from_driver(WALK, 1.0)
    for buttons in (0, 1 << vendor.BUTTON_BITS["L2"], 1 << vendor.BUTTON_BITS["B"], None):
        k.from_state(buttons, 1.002)
    assert k.due(1.011) == WALK
    off = KeepAlive(0.004, 0.010, 0.05, 0)  # the remote e-stop switched off: not watched
    off.from_driver(WALK, 1.0)
    off.from_state(L2_B, 1.002)
    assert off.due(1.011) == WALK


@pytest.mark.parametrize("args", [(0.0, 0.01, 0.05), (0.004, 0.02, 0.05), (0.004, 0.01, -1.0)])
def test_bad_arguments(args):
    with pytest.raises(ValueError):
        KeepAlive(*args)


def _lcm_url() -> str:
    """An LCM URL of its own for one test (a free UDP port)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return "udpm://239.255.76.67:%d?ttl=0" % s.getsockname()[1]


@contextlib.contextmanager
def _keepalive_process(url: str, *args: str):
    """The keep-alive process on ``url`` with PERIOD GAP HOLD [REMOTE_MASK] ``args``, once it is ready;
    killed at the end if the test did not end it."""
    proc = subprocess.Popen([sys.executable, "-m", "rbd_a1_driver.keepalive", url] + list(args),
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    try:
        assert proc.stdout.readline().startswith(b"ready SCHED_")
        yield proc
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_process_fills_the_silence_of_its_driver_and_exits_with_the_pipe():
    url = _lcm_url()
    got = []
    lc = lcm.LCM(url)
    lc.subscribe("LCM_High_Cmd", lambda _c, data: got.append((time.monotonic(), data)))
    with _keepalive_process(url, "0.004", "0.01", "0.05") as proc:
        t0 = time.monotonic()
        os.write(proc.stdin.fileno(), record(WALK, t0))  # the driver's packet; then it "stalls"
        while time.monotonic() - t0 < 0.3:
            lc.handle_timeout(10)
        assert len(got) > 30, "the keep-alive did not fill the silence"
        first = vendor.unpack(vendor.HIGH_CMD, got[0][1])
        last = vendor.unpack(vendor.HIGH_CMD, got[-1][1])
        assert first["velocity"] == pytest.approx((0.3, 0.1))
        assert last["velocity"] == (0.0, 0.0) and last["yawSpeed"] == 0.0
        speeds = [vendor.unpack(vendor.HIGH_CMD, data)["velocity"] for _t, data in got]
        moving = [i for i, v in enumerate(speeds) if v != (0.0, 0.0)]
        # repeated from gap (0.01 s) to hold (0.05 s) after the driver's send time, no longer:
        # (hold - gap) / period fills (10; +2 for the edges), then zero only. Counted, not timed:
        # our own receipt times lag the sending on a loaded machine.
        assert moving == list(range(len(moving))), "a walking fill after a zero one"
        assert len(moving) <= round((0.05 - 0.01) / 0.004) + 2, "%d walking fills" % len(moving)
        proc.stdin.close()
        assert proc.wait(5.0) == 0


def _high_state(buttons: tuple) -> bytes:
    return vendor.pack(vendor.HIGH_STATES["3.3.4"], {"mode": 2, "wirelessRemote": vendor.remote(list(buttons))})


def test_process_fills_a_stall_after_a_remote_press_with_zero_velocity():
    """The driver's last command walks; the A1 then reports L2 + B held, and the driver stalls: the
    commands the keep-alive sends after that HighState stop the robot (read on a separate LCM, in
    the order the packets reached its socket; one command may be in flight)."""
    url = _lcm_url()
    got = []
    lc = lcm.LCM(url)
    lc.subscribe("LCM_High_Cmd", lambda _c, data: got.append(vendor.unpack(vendor.HIGH_CMD, data)))
    lc.subscribe("LCM_High_State", lambda _c, data: got.append("state"))
    with _keepalive_process(url, "0.004", "0.01", "0.25", str(L2_B)) as proc:
        lc.publish("LCM_High_State", _high_state(("L1",)))  # not the combination
        t0 = time.monotonic()
        os.write(proc.stdin.fileno(), record(WALK, t0))
        while time.monotonic() - t0 < 0.08:
            lc.handle_timeout(5)
        walked = [c for c in got if c != "state"]
        assert len(walked) > 5 and all(c["velocity"] == pytest.approx((0.3, 0.1)) for c in walked)
        del got[:]
        lc.publish("LCM_High_State", _high_state(("L2", "B")))
        t_press = time.monotonic()
        while time.monotonic() - t_press < 0.1:
            lc.handle_timeout(5)
        after = got[got.index("state") + 1:]
        assert len(after) > 10, "the keep-alive stopped filling"
        moving = [c for c in after if c["velocity"] != (0.0, 0.0) or c["yawSpeed"] != 0.0]
        assert len(moving) <= 1 and moving == after[:len(moving)], \
            "the walk was repeated after the press (hold 0.25 s not yet over): %d of %d" % (len(moving), len(after))
        proc.stdin.close()
        assert proc.wait(5.0) == 0
