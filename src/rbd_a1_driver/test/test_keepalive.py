"""The keep-alive process's decisions: silent while the driver sends, repeats its last command when it
stalls, zero velocity after ``hold``; and the process itself over real LCM with the driver's pipe."""

import os
import socket
import subprocess
import sys
import time

import lcm
import pytest

from rbd_a1_driver.keepalive import KeepAlive, record, zero_velocity
from rbd_wire_oracle import unitree as vendor

WALK = vendor.pack(vendor.HIGH_CMD, {"mode": 2, "gaitType": 1, "velocity": (0.3, 0.1), "yawSpeed": 0.2})


def test_silent_while_the_driver_sends():
    k = KeepAlive(0.004, 0.010, 0.05)
    assert k.due(0.0) is None and k.wait(0.0) is None
    for i in range(100):
        k.from_driver(WALK, i * 0.004)
        assert k.due(i * 0.004 + 0.009) is None
    assert k.filled == 0


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


@pytest.mark.parametrize("args", [(0.0, 0.01, 0.05), (0.004, 0.02, 0.05), (0.004, 0.01, -1.0)])
def test_bad_arguments(args):
    with pytest.raises(ValueError):
        KeepAlive(*args)


def test_process_fills_the_silence_of_its_driver_and_exits_with_the_pipe():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        url = "udpm://239.255.76.67:%d?ttl=0" % s.getsockname()[1]
    got = []
    lc = lcm.LCM(url)
    lc.subscribe("LCM_High_Cmd", lambda _c, data: got.append((time.monotonic(), data)))
    proc = subprocess.Popen([sys.executable, "-m", "rbd_a1_driver.keepalive", url, "0.004", "0.01", "0.05"],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    try:
        assert proc.stdout.readline().startswith(b"ready SCHED_")
        t0 = time.monotonic()
        os.write(proc.stdin.fileno(), record(WALK, t0))  # the driver's packet; then it "stalls"
        while time.monotonic() - t0 < 0.3:
            lc.handle_timeout(10)
        assert len(got) > 30, "the keep-alive did not fill the silence"
        first = vendor.unpack(vendor.HIGH_CMD, got[0][1])
        last = vendor.unpack(vendor.HIGH_CMD, got[-1][1])
        assert first["velocity"] == pytest.approx((0.3, 0.1))
        assert last["velocity"] == (0.0, 0.0) and last["yawSpeed"] == 0.0
        moving = [t for t, data in got if vendor.unpack(vendor.HIGH_CMD, data)["velocity"] != (0.0, 0.0)]
        assert moving[-1] - t0 < 0.05 + 0.01  # repeated for hold after the driver's send time, no longer
        proc.stdin.close()
        assert proc.wait(5.0) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
