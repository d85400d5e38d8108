"""The opt-in rospy fast path (``rbd_bridge.ros.fastpath``): direct reads, their fallback, and without it.

Three real bridges on one master with the echo peer: one with the fast path and direct
reads (the defaults), one whose take-overs are made to fail (``test_fail_direct_reads``),
so rospy's receive threads serve it, and one with ``rospy_fast_path:=false`` (plain rospy
publishers and subscribers). All must deliver the same messages; the node's ``~stats``
service tells which path carried them (it counts in the paths themselves, so a bridge that
claims direct reads but does not use them fails here).
"""

import json
import struct
import time
import types

import pytest
from rbd_bridge_testing import OPEN, WsClient, probe_call, start_bridge, start_echo, start_probe, wait_until
from std_msgs.msg import String

from rbd_testkit import RosEnv, stop_process


@pytest.fixture(scope="module")
def bridges():
    env = RosEnv()
    try:
        start_echo(env, tick_rate=50.0)
        direct, _ = start_bridge(env, node_name="bridge_direct", **OPEN)
        fallback, _ = start_bridge(env, node_name="bridge_fallback", test_fail_direct_reads="true", **OPEN)
        plain, _ = start_bridge(env, node_name="bridge_plain", rospy_fast_path="false", **OPEN)
        start_probe(env, "probe", subs=["/plain/immediate:std_msgs/String:100"])
        yield types.SimpleNamespace(env=env, direct=direct, fallback=fallback, plain=plain)
    finally:
        env.close()


class Client(WsClient):
    def __init__(self, port):
        super().__init__("ws://127.0.0.1:%d" % port)

    def call(self, service, args=None):
        self.send({"op": "call_service", "id": "c-" + service, "service": service, "args": args or {}})
        frame = self.recv_until(lambda f: f.get("op") == "service_response" and f.get("id") == "c-" + service)
        assert frame["result"] is True, frame
        return frame["values"]

    def stats(self, node):
        values = self.call("/%s/stats" % node)
        assert values["success"] is True
        return json.loads(values["message"])


def _published(topic):
    return lambda f: f.get("op") == "publish" and f.get("topic") == topic


def _exercise(port):
    """Latched, echo (JSON and cbor-raw) and a stream of ticks through one bridge."""
    client = Client(port)
    try:
        client.send({"op": "subscribe", "topic": "/echo/latched"})
        assert client.recv_until(_published("/echo/latched"))["msg"] == {"data": "hello latched"}
        client.send({"op": "subscribe", "topic": "/echo/tick", "type": "std_msgs/Header"})
        seqs = [client.recv_until(_published("/echo/tick"))["msg"]["seq"] for _ in range(20)]
        assert seqs == sorted(seqs) and len(set(seqs)) == 20
        client.send({"op": "advertise", "topic": "/echo/in", "type": "std_msgs/String"})
        client.send({"op": "subscribe", "topic": "/echo/out", "type": "std_msgs/String"})
        raw = Client(port)
        raw.send({"op": "subscribe", "topic": "/echo/out", "type": "std_msgs/String", "compression": "cbor-raw"})
        # publish until the echo connection exists, then 50 in order
        deadline = time.monotonic() + 20
        while True:
            client.send({"op": "publish", "topic": "/echo/in", "msg": {"data": "prime"}})
            try:
                client.recv_until(_published("/echo/out"), timeout=0.3)
                break
            except TimeoutError:
                assert time.monotonic() < deadline, "echo never came back"
        for i in range(50):
            client.send({"op": "publish", "topic": "/echo/in", "msg": {"data": "n%d" % i}})
        got = []
        while len(got) < 50:
            data = client.recv_until(_published("/echo/out"))["msg"]["data"]
            if data != "prime":
                got.append(data)
        assert got == ["n%d" % i for i in range(50)]
        # cbor-raw: the serialized bytes as they came from ROS
        frame = raw.recv_until(lambda f: _published("/echo/out")(f) and b"n49" in f["msg"]["bytes"], timeout=10)
        expected = String()
        expected.deserialize(frame["msg"]["bytes"])
        assert expected.data == "n49"
        assert struct.unpack("<I", frame["msg"]["bytes"][:4])[0] == 3
        raw.close()
        return client
    except BaseException:
        client.close()
        raise


def test_direct_reads_carry_latched_echo_raw_and_ticks_without_rospy_threads(bridges):
    client = _exercise(bridges.direct)
    try:
        stats = client.stats("bridge_direct")
        assert stats["direct_reads"] is True
        assert stats["direct_read_connections"] >= 3  # latched, tick, out
        assert stats["direct_read_messages"] >= 20 + 50 + 1
        assert stats["rospy_read_messages"] == 0
        assert stats["direct_read_fallbacks"] == 0
    finally:
        client.close()


def test_a_failed_take_over_falls_back_to_rospy_with_the_same_messages(bridges):
    client = _exercise(bridges.fallback)
    try:
        stats = client.stats("bridge_fallback")
        assert stats["direct_read_connections"] == 0
        assert stats["direct_read_fallbacks"] >= 3
        assert stats["rospy_read_messages"] >= 20 + 50 + 1
    finally:
        client.close()


def test_without_the_fast_path_plain_rospy_carries_the_same(bridges):
    client = _exercise(bridges.plain)
    try:
        stats = client.stats("bridge_plain")
        assert stats["rospy_fast_path"] is False and stats["direct_reads"] is False
        assert stats["direct_read_connections"] == 0 and stats["direct_read_fallbacks"] == 0
        assert stats["rospy_read_messages"] >= 20 + 50 + 1
        # publishes right after advertise still reach a subscriber that connects afterwards
        client.send({"op": "advertise", "topic": "/plain/immediate", "type": "std_msgs/String"})
        for i in range(5):
            client.send({"op": "publish", "topic": "/plain/immediate", "msg": {"data": "p%d" % i}})
        assert wait_until(lambda: probe_call(bridges.env, "probe")["/plain/immediate"]["count"] >= 5, 10)
        got = probe_call(bridges.env, "probe")["/plain/immediate"]["messages"]
        assert [m["data"] for m in got] == ["p%d" % i for i in range(5)]
    finally:
        client.close()


def test_a_vanishing_publisher_closes_its_direct_connection_and_a_new_one_is_read(bridges):
    client = Client(bridges.direct)
    pub_cmd = ["rostopic", "pub", "-r", "20", "/direct/vanish", "std_msgs/String", "data: alive"]
    try:
        publisher = bridges.env.start(pub_cmd)
        client.send({"op": "subscribe", "topic": "/direct/vanish", "type": "std_msgs/String"})
        assert client.recv_until(_published("/direct/vanish"), timeout=20)["msg"] == {"data": "alive"}
        open_with = client.stats("bridge_direct")["direct_read_open"]
        stop_process(publisher)
        assert wait_until(lambda: client.stats("bridge_direct")["direct_read_open"] == open_with - 1, timeout=15)
        bridges.env.start(pub_cmd)
        assert client.recv_until(_published("/direct/vanish"), timeout=20)["msg"] == {"data": "alive"}
        assert client.stats("bridge_direct")["direct_read_open"] == open_with
        client.send({"op": "unsubscribe", "topic": "/direct/vanish"})
        assert wait_until(lambda: client.stats("bridge_direct")["direct_read_open"] == open_with - 1, timeout=15)
    finally:
        client.close()
