"""RobotLink against an in-process fake rosbridge server."""

import time

import pytest
from rbd_testkit import wait_for

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
        assert link.wait_connected(10)
        assert fake_bridge.wait_for(lambda: (GESTURE_TOPIC, "std_msgs/String") in fake_bridge.advertised)
        assert link.send_gesture("walk")
        assert fake_bridge.wait_for(lambda: fake_bridge.published_on(GESTURE_TOPIC) == [{"data": "walk"}])
        # heartbeat at ~2 Hz with increasing seq
        t0 = time.monotonic()
        assert fake_bridge.wait_for(lambda: len(fake_bridge.published_on(HEARTBEAT_TOPIC)) >= 5, timeout=10)
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
        assert link.wait_connected(10)
        assert link.em_stop(True) == (True, "ok")
        fake_bridge.service_handler = lambda s, a: (True, {"success": False, "message": "refused"})
        assert link.em_stop(False) == (False, "refused")
        fake_bridge.service_handler = lambda s, a: (False, "service not available")
        ok, msg = link.em_stop(True)
        assert not ok and msg
        assert [c for c in fake_bridge.service_calls] == [
            (EM_STOP_SERVICE, {"data": True}), (EM_STOP_SERVICE, {"data": False}), (EM_STOP_SERVICE, {"data": True}),
        ]
    finally:
        link.stop()


def test_reconnects_after_link_loss_and_bridge_restart(fake_bridge):
    link, got = _link(fake_bridge)
    try:
        assert link.wait_connected(10)
        fake_bridge.kick_all()
        assert wait_for(lambda: got["conn"][-1:] == [True] and False in got["conn"])
        assert link.wait_connected(10)
        assert fake_bridge.wait_for(lambda: fake_bridge.connections >= 2)
        port = fake_bridge.port
        fake_bridge.stop()
        assert wait_for(lambda: not link.connected)
        # while the bridge is gone: gestures are dropped at once (never delivered late), no blocking
        t0 = time.monotonic()
        assert link.send_gesture("spin") is False
        assert time.monotonic() - t0 < 0.05
        ok, msg = link.em_stop(True, timeout=1.0)
        assert not ok and "NOT delivered" in msg
        from fake_bridge import FakeBridge

        restarted = FakeBridge(port=port).start()
        try:
            assert link.wait_connected(10), "no reconnection after the bridge came back"
            assert restarted.wait_for(lambda: STATUS_TOPIC in restarted.subscribed)
            restarted.push(STATUS_TOPIC, {"data": "collision"})
            assert wait_for(lambda: got["status"][-1:] == ["collision"])
            link.send_gesture("wiggle")
            assert restarted.wait_for(lambda: restarted.published_on(GESTURE_TOPIC) == [{"data": "wiggle"}])
            time.sleep(0.3)
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


def test_retrying_does_not_pile_up_twisted_log_observers():
    from fake_bridge import FakeBridge
    from twisted.python import log

    b = FakeBridge().start()
    port = b.port
    b.stop()
    link = RobotLink("127.0.0.1", port, retry_s=0.05, connect_timeout_s=0.1).start()
    try:
        time.sleep(0.5)
        before = len(log.theLogPublisher.observers)
        time.sleep(1.5)  # ~10 more failed attempts
        assert len(log.theLogPublisher.observers) <= before
    finally:
        link.stop()


class SilentRelay:
    """TCP relay between the link and the bridge that can go silent without closing (WLAN out of
    range): while silent, bytes in both directions are swallowed."""

    def __init__(self, target_port):
        import socket
        import threading

        self.target_port = target_port
        self.silent = threading.Event()
        self.listener = socket.socket()
        self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.listener.bind(("127.0.0.1", 0))
        self.listener.listen(8)
        self.port = self.listener.getsockname()[1]
        self.sockets = []
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
            if not self.silent.is_set():
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
        assert link.wait_connected(10)
        time.sleep(5.0)  # answered pings keep a quiet but healthy link up
        assert link.connected and got["conn"] == [True]
        relay.silent.set()
        t0 = time.monotonic()
        ok, msg = link.em_stop(True, timeout=0.5)  # written into the silent connection
        assert not ok
        assert wait_for(lambda: not link.connected, timeout=10.0), "silent link still reported connected"
        detected = time.monotonic() - t0
        assert detected < 7.0, "silence detected only after %.1f s" % detected
        assert wait_for(lambda: got["conn"][-1:] == [False], timeout=2.0)  # the app is told
        relay.silent.clear()  # the WLAN is back: a fresh connection, the old request is gone
        assert link.wait_connected(10)
        time.sleep(1.0)
        assert (EM_STOP_SERVICE, {"data": True}) not in fake_bridge.service_calls
    finally:
        link.stop()
        relay.close()


def test_keepalive_off_keeps_a_silent_link_open(fake_bridge):
    # The behaviour the keepalive fixes (and the proof that the test above depends on it).
    relay = SilentRelay(fake_bridge.port)
    link = RobotLink("127.0.0.1", relay.port, retry_s=0.2, connect_timeout_s=1.0, keepalive_s=0.0).start()
    try:
        assert link.wait_connected(10)
        relay.silent.set()
        time.sleep(7.0)
        assert link.connected
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
        assert link.wait_connected(10), "the link thread died with the first attempt"
        assert calls["n"] >= 2
    finally:
        link.stop()
