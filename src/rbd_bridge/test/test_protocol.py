"""Session logic with a recording fake backend: no ROS, no sockets."""

import json
import time

import pytest
from rbd_bridge_testing import png_text

from rbd_bridge.core import encoding
from rbd_bridge.core.fanout import ReplayWindow, TopicMessage
from rbd_bridge.core.outqueue import OutQueue
from rbd_bridge.core.security import Policy, make_mac
from rbd_bridge.core.session import Session
from rbd_bridge.core.types import BridgeError


class FakeBackend:
    def __init__(self):
        self.calls = []
        self.pending = {}

    def advertise(self, session, topic, type_name, latch, queue_size):
        if type_name == "bad/Type":
            raise BridgeError("cannot load bad/Type")
        self.calls.append(("advertise", session.client_id, topic, type_name))

    def unadvertise(self, session, topic):
        self.calls.append(("unadvertise", session.client_id, topic))

    def publish(self, session, topic, msg):
        self.calls.append(("publish", session.client_id, topic, msg))
        return [] if "data" in msg else ["data"]

    def subscribe(self, session, topic, type_name):
        self.calls.append(("subscribe", session.client_id, topic, type_name))
        return type_name or "std_msgs/String"

    def unsubscribe(self, session, topic):
        self.calls.append(("unsubscribe", session.client_id, topic))

    def call_service(self, session, service, args, timeout, done):
        self.calls.append(("call_service", session.client_id, service, args))
        self.pending[service] = done

    def advertise_service(self, session, service, type_name):
        self.calls.append(("advertise_service", session.client_id, service))

    def unadvertise_service(self, session, service):
        self.calls.append(("unadvertise_service", session.client_id, service))

    def service_response(self, session, service, call_id, values, ok):
        self.calls.append(("service_response", service, call_id, values, ok))

    def session_closed(self, session):
        self.calls.append(("closed", session.client_id))


class Timers:
    def __init__(self):
        self.items = []

    def call_later(self, delay, fn):
        handle = Handle(delay, fn)
        self.items.append(handle)
        return handle

    def run_all(self):
        items, self.items = self.items, []
        for h in items:
            if not h.cancelled:
                h.fn()


class Handle:
    def __init__(self, delay, fn):
        self.delay = delay
        self.fn = fn
        self.cancelled = False

    def cancel(self):
        self.cancelled = True


class Clock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


def make(policy=None, client_id=1, clock=None, wall=time.time):
    backend = FakeBackend()
    out = OutQueue()
    timers = Timers()
    closed = []
    session = Session(
        client_id,
        backend,
        policy or Policy(None, None, None, None, True),
        out,
        timers.call_later,
        close=lambda code, reason: closed.append((code, reason)),
        clock=clock or Clock(),
        wall=wall,
    )
    return session, backend, out, timers, closed


def drain(out):
    frames = []
    while True:
        f = out.pop()
        if f is None:
            return frames
        frames.append(json.loads(f) if isinstance(f, str) else encoding.cbor_loads(f))


def string_message(topic, text):
    return TopicMessage(topic, lambda binary: {"data": text}, lambda: (b"raw", 1, 2))


GARBAGE = [
    "",
    "{",
    "null",
    "42",
    "-1.5",
    '"op"',
    "[1, 2, 3]",
    "[]",
    "true",
    '{"op": 5}',
    '{"no_op": 1}',
    '{"op": "no_such_op"}',
    '{"op": "publish"}',
    '{"op": "subscribe", "topic": 7}',
    '{"op": "fragment", "id": "x", "data": 1, "num": 0, "total": 1}',
    "\u0000\u0001",
    '{"op": "subscribe", "topic": "/a", "compression": "zip"}',
    "[" * 100000 + "]" * 100000,
    b"\xff\xfe\x00garbage",
    b"\x9f\x9f\x9f",
    b"",
    bytes(range(256)),
    b"\xbf" * 200,
]


def test_garbage_never_raises_and_is_silent_by_default():
    session, backend, out, _, _ = make()
    for item in GARBAGE:
        session.receive(item)
    assert drain(out) == []
    assert session.errors == len(GARBAGE)
    # the session still works afterwards
    session.receive('{"op": "publish", "topic": "/a", "msg": {"data": "x"}}')
    assert backend.calls[-1] == ("publish", 1, "/a", {"data": "x"})


def test_status_only_after_set_level_and_up_to_that_level():
    session, _, out, _, _ = make()
    session.receive('{"op": "set_level", "level": "error"}')
    session.receive("{")
    session.receive('{"op": "publish", "topic": "/a", "msg": {}}')  # missing fields -> warning
    frames = drain(out)
    assert [f["level"] for f in frames] == ["error"]
    assert "malformed JSON" in frames[0]["msg"]
    session.receive('{"op": "set_level", "level": "warning"}')
    session.receive('{"op": "publish", "id": "p1", "topic": "/a", "msg": {}}')
    frames = drain(out)
    assert frames == [
        {"op": "status", "level": "warning", "id": "p1", "msg": "publish /a: fields filled with defaults: data"}
    ]
    session.receive('{"op": "no_such_op", "id": "u1"}')
    session.receive('{"op": "publish", "id": "p2", "topic": "/a", "msg": {"data": "x"}}')  # fine: silent
    frames = drain(out)
    assert [(f["level"], f.get("id")) for f in frames] == [("error", "u1")] and "no_such_op" in frames[0]["msg"]
    session.receive('{"op": "set_level", "level": "bogus"}')  # dropped, level unchanged
    session.receive('{"op": "set_level", "level": "none"}')
    session.receive("{")
    assert drain(out) == []


def test_denied_ops_are_refused_and_reported_to_opted_in_clients():
    policy = Policy(
        publish_globs=("/rbd_gestrec/gesture",),
        subscribe_globs=("/rbd_controller/*",),
        service_globs=("/rbd_controller/em_stop",),
        param_globs=(),
    )
    session, backend, out, _, _ = make(policy)
    session.receive('{"op": "publish", "topic": "/cmd_vel", "msg": {"linear": {"x": 1}}}')
    session.receive('{"op": "advertise", "topic": "/cmd_vel", "type": "geometry_msgs/Twist"}')
    session.receive('{"op": "subscribe", "topic": "/secret"}')
    session.receive('{"op": "advertise_service", "service": "/set_body_pose", "type": "rbd_msgs/SetBodyPose"}')
    assert backend.calls == []
    assert drain(out) == []  # not opted in: silence
    session.receive('{"op": "call_service", "id": "c1", "service": "/set_body_pose", "args": {}}')
    frames = drain(out)
    assert frames[-1]["op"] == "service_response" and frames[-1]["result"] is False
    assert "allow-list" in frames[-1]["values"] and frames[-1]["id"] == "c1"
    session.receive('{"op": "set_level", "level": "error"}')
    session.receive('{"op": "publish", "id": "x", "topic": "/cmd_vel", "msg": {}}')
    frames = drain(out)
    assert frames == [
        {
            "op": "status",
            "level": "error",
            "id": "x",
            "msg": "publish /cmd_vel: not allowed by this bridge's allow-list",
        }
    ]
    session.receive('{"op": "publish", "topic": "/rbd_gestrec/gesture", "msg": {"data": "wave"}}')
    assert backend.calls[-1][0] == "publish"


def test_subscription_merging_and_unsubscribe_by_id():
    session, backend, out, _, _ = make()
    session.receive('{"op": "subscribe", "id": "a", "topic": "/t", "throttle_rate": 100, "fragment_size": 500}')
    session.receive('{"op": "subscribe", "id": "b", "topic": "/t", "throttle_rate": 20, "queue_length": 5}')
    assert [c[0] for c in backend.calls] == ["subscribe"]  # one backend subscription per client+topic
    sub = session.subs["/t"]
    assert (sub.throttle, sub.queue_length, sub.fragment_size) == (0.02, 5, 500)
    session.receive('{"op": "unsubscribe", "id": "b", "topic": "/t"}')
    assert (sub.throttle, sub.queue_length, sub.fragment_size) == (0.1, 0, 500)
    assert [c[0] for c in backend.calls] == ["subscribe"]
    session.receive('{"op": "unsubscribe", "id": "a", "topic": "/t"}')
    assert backend.calls[-1] == ("unsubscribe", 1, "/t")
    assert "/t" not in session.subs


def test_ids_are_per_connection():
    s1, backend, _, _, _ = make(client_id=1)
    s2, _, _, _, _ = make(client_id=2)
    s2.backend = backend
    for s in (s1, s2):
        s.receive('{"op": "subscribe", "id": "same", "topic": "/t"}')
    s1.receive('{"op": "unsubscribe", "id": "same", "topic": "/t"}')
    assert "/t" not in s1.subs and "/t" in s2.subs


def test_each_message_delivered_once_per_client_despite_two_subscriptions():
    session, _, out, _, _ = make()
    session.receive('{"op": "subscribe", "id": "a", "topic": "/t"}')
    session.receive('{"op": "subscribe", "id": "b", "topic": "/t"}')
    session.deliver("/t", string_message("/t", "x"))
    assert drain(out) == [{"op": "publish", "topic": "/t", "msg": {"data": "x"}}]


def test_throttle_without_queue_drops_and_with_queue_keeps_newest():
    clock = Clock()
    session, _, out, timers, _ = make(clock=clock)
    session.receive('{"op": "subscribe", "topic": "/t", "throttle_rate": 100}')
    for i in range(5):
        session.deliver("/t", string_message("/t", str(i)))
    assert [f["msg"]["data"] for f in drain(out)] == ["0"]
    clock.t += 0.2
    session.deliver("/t", string_message("/t", "5"))
    assert [f["msg"]["data"] for f in drain(out)] == ["5"]

    session2, _, out2, timers2, _ = make(clock=clock)
    session2.receive('{"op": "subscribe", "topic": "/t", "throttle_rate": 100, "queue_length": 2}')
    for i in range(5):
        session2.deliver("/t", string_message("/t", str(i)))
    assert [f["msg"]["data"] for f in drain(out2)] == ["0"]
    clock.t += 0.1
    timers2.run_all()
    clock.t += 0.1
    timers2.run_all()
    timers2.run_all()
    assert [f["msg"]["data"] for f in drain(out2)] == ["3", "4"]


def test_queue_length_bounds_backlog_of_a_topic_without_throttle():
    session, _, out, _, _ = make()
    session.receive('{"op": "subscribe", "topic": "/t", "queue_length": 3}')
    session.receive('{"op": "subscribe", "topic": "/u"}')
    for i in range(10):
        session.deliver("/t", string_message("/t", str(i)))
        session.deliver("/u", string_message("/u", str(i)))
    frames = drain(out)
    assert [f["msg"]["data"] for f in frames if f["topic"] == "/t"] == ["7", "8", "9"]
    assert len([f for f in frames if f["topic"] == "/u"]) == 10


def test_out_queue_is_bounded_by_frames_and_bytes():
    q = OutQueue(max_frames=5, max_bytes=1000)
    for i in range(100):
        q.push("%03d" % i, topic="/t")
    assert len(q) == 5 and q.dropped == 95
    assert [q.pop() for _ in range(5)] == ["095", "096", "097", "098", "099"]
    assert q.pop() is None and q.bytes == 0
    for _ in range(10):
        q.push("x" * 400)
    assert q.bytes <= 1000 and len(q) == 2


def test_out_queue_hold_collects_a_burst_and_notifies_once_on_release():
    calls = []
    q = OutQueue(notify=lambda: calls.append(len(q)))
    q.push("a")
    assert calls == [1]  # not held: every push into an empty queue notifies
    q.pop()
    q.hold()
    q.hold()
    for i in range(5):
        q.push("b%d" % i)
    q.release()
    assert calls == [1]  # still held once
    q.release()
    assert calls == [1, 5]
    while q.pop() is not None:
        pass
    q.hold()
    q.release()  # nothing waiting: no notification
    assert calls == [1, 5]


def test_fragment_size_and_compressions_on_delivery():
    session, _, out, _, _ = make()
    session.receive('{"op": "subscribe", "topic": "/t", "fragment_size": 10}')
    session.deliver("/t", string_message("/t", "hello world, this is long"))
    frames = drain(out)
    assert all(f["op"] == "fragment" for f in frames) and len(frames) > 2
    assert [f["num"] for f in frames] == list(range(frames[0]["total"]))
    whole = json.loads("".join(f["data"] for f in frames))
    assert whole == {"op": "publish", "topic": "/t", "msg": {"data": "hello world, this is long"}}

    for compression in ("cbor", "cbor-raw", "png"):
        session, _, out, _, _ = make()
        session.receive(json.dumps({"op": "subscribe", "topic": "/t", "compression": compression}))
        session.deliver("/t", string_message("/t", "hi"))
        frame = out.pop()
        if compression == "cbor":
            assert encoding.cbor_loads(frame) == {"op": "publish", "topic": "/t", "msg": {"data": "hi"}}
        elif compression == "cbor-raw":
            assert encoding.cbor_loads(frame) == {
                "op": "publish",
                "topic": "/t",
                "msg": {"secs": 1, "nsecs": 2, "bytes": b"raw"},
            }
        else:
            png = json.loads(frame)
            assert png["op"] == "png"
            assert json.loads(png_text(png["data"]))["msg"] == {"data": "hi"}


def test_incoming_fragments_reassemble_in_any_order_and_bad_ones_are_dropped():
    session, backend, out, _, _ = make()
    text = json.dumps({"op": "publish", "topic": "/a", "msg": {"data": "fragmented!"}})
    parts = [text[i : i + 7] for i in range(0, len(text), 7)]
    order = list(range(len(parts)))[::-1]
    for i in order:
        session.receive(json.dumps({"op": "fragment", "id": "f1", "data": parts[i], "num": i, "total": len(parts)}))
    assert backend.calls == [("publish", 1, "/a", {"data": "fragmented!"})]
    session.receive('{"op": "set_level", "level": "error"}')
    session.receive('{"op": "fragment", "id": "f2", "data": "x", "num": 5, "total": 2}')
    session.receive('{"op": "fragment", "id": "f3", "data": "{not json", "num": 0, "total": 1}')
    assert [f["level"] for f in drain(out)] == ["error", "error"]
    session.max_message_size = 10
    session.receive('{"op": "fragment", "id": "f4", "data": "xxxxxxxxxxxx", "num": 0, "total": 2}')
    assert "max_message_size" in drain(out)[0]["msg"]


def test_call_service_args_forms_and_response_frame():
    session, backend, out, _, _ = make()
    session.receive('{"op": "call_service", "id": 7, "service": "/s", "args": [1, 2]}')
    session.receive('{"op": "call_service", "service": "s2", "args": {"a": 1}}')
    session.receive('{"op": "call_service", "service": "/s3"}')
    session.receive('{"op": "call_service", "service": "/s4", "args": 5}')
    assert [c[2:] for c in backend.calls] == [("/s", [1, 2]), ("/s2", {"a": 1}), ("/s3", None)]
    backend.pending["/s"](True, {"sum": 3})
    backend.pending["/s2"](False, "boom")
    frames = drain(out)
    assert frames[0] == {"op": "service_response", "service": "/s", "values": {"sum": 3}, "result": True, "id": 7}
    assert frames[1] == {"op": "service_response", "service": "/s2", "values": "boom", "result": False}


def test_client_hosted_service_ops_and_teardown():
    session, backend, out, _, _ = make()
    session.receive('{"op": "advertise_service", "service": "/mine", "type": "std_srvs/SetBool"}')
    session.receive('{"op": "advertise_service", "service": "/rosapi/topics", "type": "rosapi/Topics"}')
    session.send_service_request("/mine", "req1", {"data": True})
    assert drain(out) == [{"op": "call_service", "id": "req1", "service": "/mine", "args": {"data": True}}]
    session.receive(
        '{"op": "service_response", "id": "req1", "service": "/mine", "values": {"success": true},' ' "result": true}'
    )
    session.receive('{"op": "subscribe", "topic": "/t"}')
    session.receive('{"op": "advertise", "topic": "/p", "type": "std_msgs/String"}')
    session.close()
    session.close()
    names = [c[0] for c in backend.calls]
    assert names == ["advertise_service", "service_response", "subscribe", "advertise", "closed"]
    session.receive('{"op": "publish", "topic": "/p", "msg": {"data": "late"}}')
    assert names == [c[0] for c in backend.calls]


def test_auth_required_before_anything_else():
    secret = "0123456789abcdef"
    policy = Policy(None, None, None, None, secret=secret)
    wall = 1000.0
    # as rosbridge: any op but auth on an unauthenticated connection closes it
    for first in ('{"op": "set_level", "level": "error"}', '{"op": "subscribe", "topic": "/t"}'):
        session, backend, out, _, closed = make(policy, wall=lambda: wall)
        session.receive(first)
        session.receive('{"op": "subscribe", "topic": "/t"}')
        assert closed == [(1008, "authentication required")] and drain(out) == []
        assert backend.calls == [("closed", 1)]  # released at once, nothing done in ROS
    session, backend, out, _, closed = make(policy, wall=lambda: wall)
    mac = make_mac(secret, "client", "dest", "rand", 1000, "admin", 2000)
    good = {
        "op": "auth",
        "mac": mac,
        "client": "client",
        "dest": "dest",
        "rand": "rand",
        "t": 1000,
        "level": "admin",
        "end": 2000,
    }
    session.receive(json.dumps(good))
    assert session.authenticated and not closed
    session.receive('{"op": "subscribe", "topic": "/t"}')
    assert backend.calls[-1][0] == "subscribe"

    for bad in (dict(good, mac="0" * 128), dict(good, t=900), dict(good, end=999), dict(good, rand=None)):
        s2, b2, _, _, closed2 = make(policy, wall=lambda: wall)
        s2.receive(json.dumps(bad))
        s2.receive('{"op": "subscribe", "topic": "/t"}')
        assert not s2.authenticated and closed2 and b2.calls == [("closed", 1)]


@pytest.mark.parametrize("level", ["info"])
def test_info_level_reports_successes(level):
    session, _, out, _, _ = make()
    session.receive('{"op": "set_level", "level": "%s"}' % level)
    session.receive('{"op": "subscribe", "id": "s1", "topic": "/t"}')
    assert drain(out) == [{"op": "status", "level": "info", "id": "s1", "msg": "subscribed to /t"}]


def test_replay_window_keeps_the_newest_publishes_for_one_window():
    now = [10.0]
    window = ReplayWindow(1.0, 3, latch=False, clock=lambda: now[0])
    for i in range(5):
        window.record(i)
    assert window.replay() == [2, 3, 4]  # bounded: the newest limit messages
    now[0] = 10.999
    assert window.replay() == [2, 3, 4]
    now[0] = 11.0  # closed: nothing for later subscribers, nothing kept
    assert window.replay() == []
    window.record(5)
    assert list(window.messages) == []
    latched = ReplayWindow(1.0, 10, latch=True, clock=lambda: 0.0)
    latched.record("a")
    latched.record("b")
    assert latched.replay() == ["a"]  # rospy's latch resends "b" itself
    off = ReplayWindow(0, 10, latch=False, clock=lambda: 0.0)
    off.record("x")
    assert off.replay() == []
