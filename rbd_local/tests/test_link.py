"""RobotLink against an in-process fake rosbridge server."""

import threading
import time

import pytest
from rbd_testkit import stays_unchanged, wait_for

from rbd_local.link import (
    EM_STOP_SERVICE,
    GESTURE_TOPIC,
    HEARTBEAT_TOPIC,
    PATH_QUEUE_TOPIC,
    STATE_TOPIC,
    STATUS_TOPIC,
    RobotLink,
)


def _link(bridge, **kw):
    got = {"status": [], "state": [], "moves": [], "conn": []}
    link = RobotLink(
        "127.0.0.1", bridge.port, retry_s=0.2, connect_timeout_s=1.0,
        on_status=got["status"].append, on_state=got["state"].append,
        on_path_queue=got["moves"].append, on_connection=got["conn"].append, **kw,
    )
    return link.start(), got


def test_gesture_heartbeat_and_subscriptions(fake_bridge):
    link, got = _link(fake_bridge)
    try:
        assert link.wait_connected(30)
        assert fake_bridge.wait_for(lambda: (GESTURE_TOPIC, "std_msgs/String") in fake_bridge.advertised)
        assert link.send_gesture("walk")
        assert fake_bridge.wait_for(lambda: fake_bridge.published_on(GESTURE_TOPIC) == [{"data": "walk"}])
        # heartbeat at ~2 Hz with increasing seq
        t0 = time.monotonic()
        assert fake_bridge.wait_for(lambda: len(fake_bridge.published_on(HEARTBEAT_TOPIC)) >= 5)
        beats = fake_bridge.published_on(HEARTBEAT_TOPIC)
        assert 1.2 < time.monotonic() - t0 + 0.5 < 6.0
        seqs = [b["seq"] for b in beats]
        assert seqs == sorted(seqs) and beats[0]["frame_id"] == "rbd_local"
        wanted = {STATUS_TOPIC, STATE_TOPIC, PATH_QUEUE_TOPIC}
        assert fake_bridge.wait_for(lambda: wanted <= set(fake_bridge.subscribed))
        assert fake_bridge.subscribed[PATH_QUEUE_TOPIC] == "rbd_msgs/PathQueue"
        fake_bridge.push(STATUS_TOPIC, {"data": "running"})
        fake_bridge.push(STATE_TOPIC, {"data": "EXECUTING"})
        fake_bridge.push(PATH_QUEUE_TOPIC, {"command": "walk", "names": ["a", "b", "c"], "poses": []})
        fake_bridge.push(STATUS_TOPIC, {"nodata": 1})  # malformed: ignored, no crash
        fake_bridge.push(PATH_QUEUE_TOPIC, {"names": "x"})  # malformed: ignored
        fake_bridge.push(STATUS_TOPIC, {"data": "idle"})
        assert wait_for(lambda: got["status"] == ["running", "idle"])
        assert got["state"] == ["EXECUTING"] and got["moves"] == [["a", "b", "c"]]
        assert link.connected
    finally:
        link.stop()


def test_em_stop_calls_the_service_and_reports_the_answer(fake_bridge):
    link, _ = _link(fake_bridge)
    try:
        assert link.wait_connected(30)
        # (answers are under test here, not speed: a generous timeout for a loaded machine)
        assert link.em_stop(True, timeout=10) == (True, "ok")
        fake_bridge.service_handler = lambda s, a: (True, {"success": False, "message": "refused"})
        assert link.em_stop(False, timeout=10) == (False, "refused")
        fake_bridge.service_handler = lambda s, a: (False, "service not available")
        ok, msg = link.em_stop(True, timeout=10)
        assert not ok and msg
        assert [c for c in fake_bridge.service_calls] == [
            (EM_STOP_SERVICE, {"data": True}), (EM_STOP_SERVICE, {"data": False}), (EM_STOP_SERVICE, {"data": True}),
        ]
    finally:
        link.stop()


def test_em_stop_is_called_again_when_the_connection_drops_before_the_answer(fake_bridge):
    # A lossy WLAN: the connection is given up with the e-stop call in flight. The call is made
    # again on the next connection within the caller's timeout (before, it waited out the whole
    # timeout on the dead connection and reported the e-stop as not delivered).
    calls = []

    def handler(service, args):
        calls.append((service, args))
        return None if len(calls) == 1 else (True, {"success": True, "message": "engaged"})

    fake_bridge.service_handler = handler
    link, got = _link(fake_bridge)
    try:
        assert link.wait_connected(30)
        t0 = time.monotonic()
        assert link.em_stop(True, timeout=20) == (True, "engaged")
        assert time.monotonic() - t0 < 15.0, "the call waited out its timeout on the dead connection"
        assert calls == [(EM_STOP_SERVICE, {"data": True})] * 2
        assert False in got["conn"] and fake_bridge.connections >= 2
    finally:
        link.stop()


def test_reconnects_after_link_loss_and_bridge_restart(fake_bridge):
    link, got = _link(fake_bridge)
    try:
        assert link.wait_connected(30)
        fake_bridge.kick_all()
        assert wait_for(lambda: got["conn"][-1:] == [True] and False in got["conn"])
        assert link.wait_connected(30)
        assert fake_bridge.wait_for(lambda: fake_bridge.connections >= 2)
        port = fake_bridge.port
        fake_bridge.stop()
        assert wait_for(lambda: not link.connected)
        # while the bridge is gone: gestures are dropped at once (never delivered late), no blocking
        t0 = time.monotonic()
        assert link.send_gesture("spin") is False
        assert time.monotonic() - t0 < 0.5  # (a connection attempt would take connect_timeout_s, 1 s)
        ok, msg = link.em_stop(True, timeout=1.0)
        assert not ok and "NOT delivered" in msg
        from fake_bridge import FakeBridge

        restarted = FakeBridge(port=port).start()
        try:
            assert link.wait_connected(30), "no reconnection after the bridge came back"
            assert restarted.wait_for(lambda: STATUS_TOPIC in restarted.subscribed)
            restarted.push(STATUS_TOPIC, {"data": "collision"})
            assert wait_for(lambda: got["status"][-1:] == ["collision"])
            link.send_gesture("wiggle")
            assert restarted.wait_for(lambda: restarted.published_on(GESTURE_TOPIC) == [{"data": "wiggle"}])
            # "spin" was queued before "wiggle" on the one ordered connection: had it been sent late,
            # it would have arrived first. wiggle's arrival is the proof; no waiting for nothing.
            assert {"data": "spin"} not in restarted.published_on(GESTURE_TOPIC)
            assert link.dropped_gestures >= 1
        finally:
            restarted.stop()
    finally:
        link.stop()


def test_never_blocks_without_a_bridge():
    from fake_bridge import FakeBridge

    b = FakeBridge().start()
    port = b.port
    b.stop()  # nothing listens on this port now
    link = RobotLink("127.0.0.1", port, retry_s=0.2, connect_timeout_s=0.5).start()
    try:
        t0 = time.monotonic()
        for _ in range(100):
            link.send_gesture("walk")
        assert time.monotonic() - t0 < 0.1
        assert not link.connected
    finally:
        link.stop()


def test_bad_arguments():
    with pytest.raises(ValueError):
        RobotLink("", 9090)
    with pytest.raises(ValueError):
        RobotLink("127.0.0.1", 70000)
    with pytest.raises(ValueError):
        RobotLink("127.0.0.1", 9090, retry_s=0)
    link = RobotLink("127.0.0.1", 9090)
    with pytest.raises(ValueError):
        link.send_gesture("")


def test_retrying_does_not_pile_up_twisted_log_observers(monkeypatch):
    from fake_bridge import FakeBridge
    from twisted.python import log

    from rbd_local.link import connection

    attempts = []
    real = connection.open_client

    def counted(*args, **kw):
        attempts.append(1)
        return real(*args, **kw)

    monkeypatch.setattr(connection, "open_client", counted)
    b = FakeBridge().start()
    port = b.port
    b.stop()
    link = RobotLink("127.0.0.1", port, retry_s=0.05, connect_timeout_s=0.1).start()
    try:
        assert wait_for(lambda: len(attempts) >= 3, 10.0), "no connection attempts"
        before = len(log.theLogPublisher.observers)
        n = len(attempts)
        # ~0.2 s each on an idle machine; a bare machine's make test (nice 10 beside the serial lane's
        # simulations) made fewer than 10 in 20 s once. What counts is that they do not pile up observers.
        assert wait_for(lambda: len(attempts) >= n + 10, 60.0), "not 10 more attempts in 60 s: %d" % (len(attempts) - n)
        assert len(log.theLogPublisher.observers) <= before
    finally:
        link.stop()


class SilentRelay:
    """TCP relay between the link and the bridge that can go silent without closing (WLAN out of
    range): while silent, bytes in both directions are swallowed."""

    def __init__(self, target_port):
        import socket

        self.target_port = target_port
        self.silent = threading.Event()
        self.listener = socket.socket()
        self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.listener.bind(("127.0.0.1", 0))
        self.listener.listen(8)
        self.port = self.listener.getsockname()[1]
        self.sockets = []
        self.swallowed = 0  # chunks dropped while silent
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self):
        import socket
        import threading

        while True:
            try:
                client, _ = self.listener.accept()
            except OSError:
                return
            upstream = socket.create_connection(("127.0.0.1", self.target_port))
            self.sockets += [client, upstream]
            for a, b in ((client, upstream), (upstream, client)):
                threading.Thread(target=self._pipe, args=(a, b), daemon=True).start()

    def _pipe(self, src, dst):
        while True:
            try:
                data = src.recv(65536)
            except OSError:
                data = b""
            if not data:
                for s in (src, dst):
                    try:
                        s.close()
                    except OSError:
                        pass
                return
            if self.silent.is_set():
                self.swallowed += 1
                continue
            try:
                dst.sendall(data)
            except OSError:
                return

    def close(self):
        self.listener.close()
        for s in self.sockets:
            try:
                s.close()
            except OSError:
                pass


def test_silent_link_is_dropped_by_keepalive_and_stale_estop_never_arrives(fake_bridge):
    relay = SilentRelay(fake_bridge.port)
    got = {"conn": []}
    link = RobotLink("127.0.0.1", relay.port, retry_s=0.2, connect_timeout_s=1.0, keepalive_s=5.0,
                     on_connection=got["conn"].append).start()
    try:
        assert link.wait_connected(30)
        # answered pings keep a quiet but healthy link up: six pings (5 s at one per second) on it
        assert wait_for(lambda: link.keepalive.pings_sent >= 6, 20.0), "the keepalive sent no pings"
        assert link.connected and got["conn"] == [True]
        relay.silent.set()
        t0 = time.monotonic()
        ok, msg = link.em_stop(True, timeout=0.5)  # written into the silent connection
        assert not ok
        assert wait_for(lambda: not link.connected, timeout=10.0), "silent link still reported connected"
        detected = time.monotonic() - t0
        assert detected < 7.0, "silence detected only after %.1f s" % detected
        assert wait_for(lambda: got["conn"][-1:] == [False], timeout=10.0)  # the app is told
        relay.silent.clear()  # the WLAN is back: a fresh connection, the old request is gone
        assert link.wait_connected(30)
        # proof that the new connection delivers calls: a release, answered; the stale engage
        # written into the silent connection would have come before it
        ok, msg = link.em_stop(False, timeout=10.0)
        assert ok, msg
        assert (EM_STOP_SERVICE, {"data": False}) in fake_bridge.service_calls
        assert (EM_STOP_SERVICE, {"data": True}) not in fake_bridge.service_calls
    finally:
        link.stop()
        relay.close()


def _assert_stays_connected(link, seconds, during, began):
    """The link stays up (same connection) for ``seconds`` after ``began()`` proves ``during`` started."""
    stays_unchanged(lambda: (link.connected, link.connect_count), began, hold=seconds, timeout=10.0,
                    what="the link's connection", proof="the start of " + during)


def test_a_stall_of_the_laptop_is_not_taken_for_a_silent_robot(fake_bridge):
    # The keepalive counts from pings this process actually sent and judges after reading what
    # came back: a stall of the laptop's own event loop (longer than the keepalive; CI's niced
    # test processes see such stalls) must not drop a healthy link.
    from twisted.internet import reactor

    got = {"conn": []}
    link = RobotLink("127.0.0.1", fake_bridge.port, retry_s=0.2, connect_timeout_s=1.0, keepalive_s=2.0,
                     on_connection=got["conn"].append).start()
    try:
        assert link.wait_connected(30)
        assert wait_for(lambda: link.keepalive.pings_sent >= 2 and link.keepalive.unanswered is None, 10.0)
        stalled = threading.Event()

        def stall():
            stalled.set()
            time.sleep(5.0)  # the reactor stalls for 2.5 keepalives

        reactor.callFromThread(stall)
        _assert_stays_connected(link, 8.0, "a stall of the laptop", stalled.is_set)
        assert got["conn"] == [True] and link.connect_count == 1
    finally:
        link.stop()


def test_a_stall_of_the_whole_process_ending_just_before_the_verdict_keeps_the_link(fake_bridge):
    # CI: the niced test process (link, reactor and the in-process bridge alike) stalled for most
    # of a keepalive; the reactor woke just before its verdict was due, the bridge's pong just
    # after, and a healthy link was dropped. Here: the bridge stops answering, the first unanswered
    # ping goes out, the reactor stalls until 0.2 s before the verdict and the bridge answers 0.5 s
    # after it. The silence must span KEEPALIVE_PINGS pings this process sent, so the link stays.
    from twisted.internet import reactor

    keepalive = 2.0
    got = {"conn": []}
    link = RobotLink("127.0.0.1", fake_bridge.port, retry_s=0.2, connect_timeout_s=1.0, keepalive_s=keepalive,
                     on_connection=got["conn"].append).start()
    try:
        assert link.wait_connected(30)
        assert wait_for(lambda: link.keepalive.pings_sent >= 2 and link.keepalive.unanswered is None, 10.0)
        bridge_stalled = threading.Event()

        def stall_bridge():
            bridge_stalled.set()
            # a ping goes out and stays unanswered
            sent = wait_for(lambda: link.keepalive.unanswered, 10.0, 0.005, what="an unanswered ping")
            reactor.callFromThread(time.sleep, max(0.0, sent + keepalive - 0.2 - time.monotonic()))
            time.sleep(max(0.0, sent + keepalive + 0.5 - time.monotonic()))

        fake_bridge._loop.call_soon_threadsafe(stall_bridge)
        assert bridge_stalled.wait(10)
        _assert_stays_connected(link, keepalive + 3.0, "a stall of the whole process", bridge_stalled.is_set)
        assert got["conn"] == [True] and link.connect_count == 1
    finally:
        link.stop()


def test_keepalive_off_keeps_a_silent_link_open(fake_bridge):
    # The behaviour the keepalive fixes (and the proof that the silent-link test depends on it).
    relay = SilentRelay(fake_bridge.port)
    link = RobotLink("127.0.0.1", relay.port, retry_s=0.2, connect_timeout_s=1.0, keepalive_s=0.0).start()
    try:
        assert link.wait_connected(30)
        relay.silent.set()
        # proof the silence bites: the link's heartbeats (2 Hz) are being swallowed
        n = relay.swallowed
        stays_unchanged(lambda: (link.connected, link.connect_count), lambda: relay.swallowed > n + 2, hold=7.0,
                        what="the link's connection", proof="heartbeats swallowed by the silent relay")
    finally:
        relay.silent.clear()
        link.stop()
        relay.close()


def test_link_thread_survives_an_exception_in_a_connection_attempt(fake_bridge, monkeypatch):
    real = RobotLink._connect
    calls = {"n": 0}

    def flaky(self):
        calls["n"] += 1
        if calls["n"] == 1:
            raise KeyError(24)  # what a reactor race once raised inside roslibpy/twisted
        return real(self)

    monkeypatch.setattr(RobotLink, "_connect", flaky)
    link = RobotLink("127.0.0.1", fake_bridge.port, retry_s=0.2, connect_timeout_s=1.0).start()
    try:
        assert link.wait_connected(30), "the link thread died with the first attempt"
        assert calls["n"] >= 2
    finally:
        link.stop()


# ------------------------------------------------------------- the robot's tricks (teach mode)
TRICKS = {"walk": [{"name": "walk forward 0.6 m", "x": 0.6}, {"name": "return", "x": 0.0}],
          "bow": [{"name": "bow: nose down", "pitch": 0.35}, {"name": "stand up", "pitch": 0.0}]}


def test_get_tricks_reads_the_navigation_parameter_through_rosapi(fake_bridge):
    import json

    from rbd_local.link import TRICKS_PARAM

    answers = {"value": json.dumps(TRICKS)}

    def handler(service, args):
        if service == "/rosapi/get_param":
            return (True, answers) if isinstance(answers, dict) else (False, answers)
        return True, {}

    fake_bridge.service_handler = handler
    link, _got = _link(fake_bridge)
    try:
        assert link.wait_connected(30)
        assert link.get_tricks(5.0) == {"walk": ["walk forward 0.6 m", "return"], "bow": ["bow: nose down", "stand up"]}
        assert ("/rosapi/get_param", {"name": TRICKS_PARAM}) in fake_bridge.service_calls
        answers = {"value": json.dumps({"walk": [{"x": 1.0}]})}  # a step without a name
        with pytest.raises(ValueError, match="has no name"):
            link.get_tricks(5.0)
        answers = {"value": "null"}  # rosapi's answer for a parameter that is not set
        with pytest.raises(ValueError, match="not set"):
            link.get_tricks(5.0)
        answers = "parameter /rbd_navigation/tricks is not allowed by this bridge's allow-list"
        with pytest.raises(ValueError, match="allow-list"):
            link.get_tricks(5.0)
    finally:
        link.stop()
    with pytest.raises(ConnectionError):
        link.get_tricks(1.0)


# ------------------------------------------------------------------------- the robot's camera
def _jpeg_msg(value, secs, nsecs=0, fmt="bgr8; jpeg compressed bgr8", size=(64, 48)):
    import base64

    import cv2
    import numpy as np

    img = np.full((size[1], size[0], 3), value, np.uint8)
    ok, buf = cv2.imencode(".jpg", img)
    assert ok
    return {"header": {"seq": 0, "stamp": {"secs": secs, "nsecs": nsecs}, "frame_id": "zed2_left_camera_optical_frame"},
            "format": fmt, "data": base64.b64encode(buf.tobytes()).decode("ascii")}


def test_camera_frames_arrive_throttled_newest_only_and_decoded(fake_bridge):
    import threading

    from rbd_local.gestures.robot_camera import RobotCameraSource
    from rbd_local.link import CAMERA_TOPIC

    source = RobotCameraSource(idle_timeout_s=5.0)
    link, _got = _link(fake_bridge, on_camera=source.push, camera_throttle_ms=33)
    try:
        assert link.wait_connected(30)
        assert fake_bridge.wait_for(lambda: CAMERA_TOPIC in fake_bridge.subscribed)
        op = [o for o in fake_bridge.subscribe_ops if o["topic"] == CAMERA_TOPIC][0]
        assert op["type"] == "sensor_msgs/CompressedImage"
        assert op["throttle_rate"] == 33 and op["queue_length"] == 1  # the bridge keeps only the newest
        now = int(time.time())
        fake_bridge.push(CAMERA_TOPIC, _jpeg_msg(40, now, 0))
        assert wait_for(lambda: source.received == 1)
        t, frame = next(iter(source))
        assert t == 0.0 and frame.shape == (48, 64, 3) and abs(float(frame.mean()) - 40) < 3
        # two frames arrive while the loop is busy: only the newer one is shown
        fake_bridge.push(CAMERA_TOPIC, _jpeg_msg(80, now, 100_000_000))
        fake_bridge.push(CAMERA_TOPIC, _jpeg_msg(120, now, 200_000_000))
        assert wait_for(lambda: source.received == 3)
        t, frame = next(source)
        assert t == pytest.approx(0.2) and abs(float(frame.mean()) - 120) < 3
        assert source.dropped == 1
        # broken messages are skipped (counted), never a crash; an older stamp is not shown
        bads = ({"format": "rgb8", "data": _jpeg_msg(1, now)["data"]}, {"format": "jpeg", "data": "@@@"},
                {"format": "jpeg", "data": "AAAA"}, _jpeg_msg(9, now, 100_000_000))
        for i, bad in enumerate(bads):
            got = []
            source.push(bad)
            reader = threading.Thread(target=lambda out=got: out.append(next(source, None)), daemon=True)
            reader.start()
            assert wait_for(lambda n=i + 1: source.bad == n), "the bad frame was not seen and skipped"
            fake_bridge.push(CAMERA_TOPIC, _jpeg_msg(200, now + 1 + i, 0))
            reader.join(10)
            assert got and got[0] is not None, "the source stalled after a bad frame"
            assert abs(float(got[0][1].mean()) - 200) < 3
        assert source.bad == len(bads)
        st = source.stats()
        assert st["received"] >= 7 and st["shown"] == 6 and st["transport_ms"]["median"] is not None
    finally:
        source.close()
        link.stop()
    assert next(source, "end") == "end"  # a closed source ends the iteration


# ------------------------------------------------------------------------- the robot's preflight
def test_preflight_test_reports_have_the_robots_message_fields():
    import preflight_reports as pr

    assert list(pr.report()) == pr.msg_fields("PreflightReport")
    assert list(pr.report()["checks"][0]) == pr.msg_fields("PreflightCheck")
    assert pr.msg_fields("PreflightCheck") == ["key", "name", "status", "value", "hint"]


def test_run_preflight_calls_the_service_and_returns_the_report(fake_bridge):
    import preflight_reports as pr

    from rbd_local.link import PREFLIGHT_SERVICE

    answers = {"report": pr.report()}

    def handler(service, args):
        if service == PREFLIGHT_SERVICE:
            return (True, answers) if isinstance(answers, dict) else (False, answers)
        return True, {}

    fake_bridge.service_handler = handler
    link, _got = _link(fake_bridge)
    try:
        assert link.wait_connected(30)
        rep = link.run_preflight(5.0)
        assert (PREFLIGHT_SERVICE, {"duration": 0.0}) in fake_bridge.service_calls
        assert rep["ready"] is False and rep["duration"] == 3.0
        assert abs(rep["stamp"] - 1764084662.25) < 1e-6
        assert [(c["name"], c["status"]) for c in rep["checks"]] == [
            ("A1 HighState", "PASS"), ("LiDAR /ouster/points", "FAIL"), ("LiDAR cloud layout", "SKIP")]
        assert rep["checks"][1]["value"] == "no message in 3.0 s"
        assert rep["checks"][1]["hint"].startswith("is ouster-ros running")
        assert rep["mounts_file"] == "/opt/robodog/mounts.yaml"
        link.run_preflight(5.0, duration=6.0)
        assert fake_bridge.service_calls[-1] == (PREFLIGHT_SERVICE, {"duration": 6.0})
        with pytest.raises(ValueError):
            link.run_preflight(5.0, duration=11.0)  # refused before anything is sent
        assert fake_bridge.service_calls[-1] == (PREFLIGHT_SERVICE, {"duration": 6.0})
        # the robot without preflight_server: rbd_bridge answers result false with its reason
        answers = "service /preflight/run does not exist"
        with pytest.raises(ValueError, match="does not exist.*preflight_server"):
            link.run_preflight(5.0)
        answers = {"report": dict(pr.report(), checks=[pr.check("x", "X", "MAYBE", "")])}
        with pytest.raises(ValueError, match="malformed"):
            link.run_preflight(5.0)
    finally:
        link.stop()
    with pytest.raises(ConnectionError, match="no connection"):
        link.run_preflight(1.0)


def test_run_preflight_without_a_bridge_fails_at_once():
    link = RobotLink("127.0.0.1", 9, retry_s=0.2, connect_timeout_s=0.3).start()
    try:
        t0 = time.monotonic()
        with pytest.raises(ConnectionError, match="no connection"):
            link.run_preflight(5.0)
        assert time.monotonic() - t0 < 1.0
    finally:
        link.stop()


def test_latched_preflight_report_reaches_the_callback(fake_bridge):
    import preflight_reports as pr

    from rbd_local.link import PREFLIGHT_TOPIC

    reports = []
    link, _got = _link(fake_bridge, on_preflight=reports.append)
    try:
        assert link.wait_connected(30)
        assert fake_bridge.wait_for(lambda: PREFLIGHT_TOPIC in fake_bridge.subscribed)
        assert fake_bridge.subscribed[PREFLIGHT_TOPIC] == "rbd_msgs/PreflightReport"
        fake_bridge.push(PREFLIGHT_TOPIC, pr.report())
        fake_bridge.push(PREFLIGHT_TOPIC, {"ready": "yes"})  # malformed: ignored, no crash
        fake_bridge.push(PREFLIGHT_TOPIC, pr.all_pass())
        assert wait_for(lambda: len(reports) == 2)
        assert [r["ready"] for r in reports] == [False, True]
        assert [c["status"] for c in reports[0]["checks"]] == ["PASS", "FAIL", "SKIP"]
    finally:
        link.stop()
