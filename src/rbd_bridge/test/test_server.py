"""The RFC 6455 transport with a fake backend (no ROS): handshake, framing, limits, flow control."""

import asyncio
import json
import socket
import threading

import pytest
from websockets.exceptions import ConnectionClosed
from websockets.frames import Frame, Opcode
from websockets.sync.client import connect

from rbd_bridge.core import websocket
from rbd_bridge.core.fanout import TopicMessage
from rbd_bridge.core.security import Policy
from rbd_bridge.core.websocket import BridgeServer
from rbd_testkit import wait_for


class EchoBackend:
    """publish on /loop comes straight back to every subscriber of /loop."""

    def __init__(self):
        self.sessions = set()
        self.closed = []

    def begin_batch(self):
        pass

    def end_batch(self):
        pass

    def advertise(self, session, topic, type_name, latch, queue_size):
        pass

    def publish(self, session, topic, msg):
        message = TopicMessage(topic, lambda binary: dict(msg))
        for s in list(self.sessions):
            s.deliver(topic, message)
        return []

    def subscribe(self, session, topic, type_name):
        self.sessions.add(session)
        return "std_msgs/String"

    def unsubscribe(self, session, topic):
        self.sessions.discard(session)

    def session_closed(self, session):
        self.sessions.discard(session)
        self.closed.append(session.client_id)


@pytest.fixture
def server(request):
    ping = getattr(request, "param", None)
    loop = asyncio.new_event_loop()
    backend = EchoBackend()
    srv = BridgeServer(loop, backend, Policy(None, None, None, None), port=0, max_message_size=100000,
                       max_queue_frames=50, ping_interval=ping, ping_timeout=ping)
    port = loop.run_until_complete(srv.start())
    thread = threading.Thread(target=loop.run_forever, daemon=True)
    thread.start()
    yield srv, backend, port
    asyncio.run_coroutine_threadsafe(srv.stop(), loop).result(10)
    loop.call_soon_threadsafe(loop.stop)
    thread.join(10)
    loop.close()


def test_fragmented_client_messages_and_big_server_frames(server):
    _, _, port = server
    ws = connect("ws://127.0.0.1:%d" % port, compression=None, max_size=None)
    ws.send(json.dumps({"op": "subscribe", "topic": "/loop"}))
    big = "y" * 70000
    frame = json.dumps({"op": "publish", "topic": "/loop", "msg": {"data": big}})
    ws.send([frame[:10], frame[10:40000], frame[40000:]])  # three WebSocket frames, one message
    got = json.loads(ws.recv(timeout=5))
    assert got == {"op": "publish", "topic": "/loop", "msg": {"data": big}}
    ws.send(frame.encode())  # binary frame holding UTF-8 JSON is accepted too
    assert json.loads(ws.recv(timeout=5))["msg"]["data"] == big
    ws.close()


def test_unmasking_without_websockets_speedups(server, monkeypatch):
    """Without websockets' C helper (as on the robot) wsproto's masker unmasks the fast path's frames."""
    monkeypatch.setattr(websocket, "_apply_mask", None)
    _, _, port = server
    ws = connect("ws://127.0.0.1:%d" % port, compression=None, max_size=None)
    ws.send(json.dumps({"op": "subscribe", "topic": "/loop"}))
    for data in ("x", "é", "z" * 131, "\u20ac" * 23335):  # frames of 4n+1, +2, +3 (16-bit length), +1 (64-bit)
        frame = json.dumps({"op": "publish", "topic": "/loop", "msg": {"data": data}}, ensure_ascii=False)
        ws.send(frame)
        assert json.loads(ws.recv(timeout=5))["msg"]["data"] == data
        ws.send(frame.encode())
        assert json.loads(ws.recv(timeout=5))["msg"]["data"] == data
    ws.close()


def test_non_websocket_http_is_refused_and_unmasked_frames_close(server):
    _, _, port = server
    s = socket.create_connection(("127.0.0.1", port))
    s.sendall(b"GET / HTTP/1.1\r\nHost: x\r\n\r\n")
    assert s.recv(100).startswith(b"HTTP/1.1 426")
    s.close()
    s = socket.create_connection(("127.0.0.1", port))
    s.sendall(b"GET / HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
              b"Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n")
    reply = s.recv(1000)
    assert reply.startswith(b"HTTP/1.1 101") and b"s3pPLMBiTxaQ9kYGzzhZRbK+xOo=" in reply
    s.sendall(b"\x81\x02{}")  # not masked
    data = b""
    s.settimeout(5)
    while True:
        chunk = s.recv(100)
        if not chunk:
            break
        data += chunk
    assert data[:1] == b"\x88" and data[2:4] == (1002).to_bytes(2, "big") and b"masked" in data
    s.close()


def test_invalid_utf8_in_a_text_frame_closes_with_1007(server):
    _, backend, port = server
    ws = connect("ws://127.0.0.1:%d" % port, compression=None)
    ws.send(json.dumps({"op": "subscribe", "topic": "/loop"}))  # a valid frame first: the session is up
    assert wait_for(lambda: backend.sessions, 5.0, 0.02)
    ws.socket.sendall(Frame(Opcode.TEXT, b'{"op": "\xff\xfe"}').serialize(mask=True))  # made by websockets
    with pytest.raises(ConnectionClosed) as info:
        ws.recv(timeout=5)
    assert info.value.rcvd is not None and info.value.rcvd.code == 1007  # RFC 6455 section 8.1


def test_common_frames_then_the_stream_handed_to_wsproto(server):
    """Frames made by websockets: the fast path's frames (a big one over several reads), then a
    fragmented message hands the stream to wsproto mid-read; every message once, in order,
    pings answered before and after, invalid UTF-8 closes with 1007 on the wsproto side too."""
    _, backend, port = server
    ws = connect("ws://127.0.0.1:%d" % port, compression=None, max_size=None)
    ws.send(json.dumps({"op": "subscribe", "topic": "/loop"}))
    assert wait_for(lambda: backend.sessions, 5.0, 0.02)
    assert ws.ping(b"before").wait(5)

    def pub(data):
        return json.dumps({"op": "publish", "topic": "/loop", "msg": {"data": data}}).encode()

    big = "a" * 70000
    frames = [
        Frame(Opcode.TEXT, pub(big)),
        Frame(Opcode.BINARY, pub("b")),
        Frame(Opcode.TEXT, pub("c")[:7], fin=False),  # fragmented: wsproto from here on
        Frame(Opcode.CONT, pub("c")[7:]),
        Frame(Opcode.TEXT, pub("d")),
    ]
    ws.socket.sendall(b"".join(f.serialize(mask=True) for f in frames))
    got = [json.loads(ws.recv(timeout=5))["msg"]["data"] for _ in range(4)]
    assert got == [big, "b", "c", "d"]
    assert ws.ping(b"after").wait(5)
    ws.socket.sendall(Frame(Opcode.TEXT, b'{"op": "\xff"}').serialize(mask=True))
    with pytest.raises(ConnectionClosed) as info:
        ws.recv(timeout=5)
    assert info.value.rcvd is not None and info.value.rcvd.code == 1007


def test_oversized_message_closes_with_1009(server):
    _, _, port = server
    ws = connect("ws://127.0.0.1:%d" % port, compression=None)
    with pytest.raises(ConnectionClosed) as info:
        ws.send("x" * 100001)
        ws.recv(timeout=5)
    assert info.value.rcvd.code == 1009


@pytest.mark.parametrize("server", [0.5], indirect=True)
def test_silent_client_is_dropped_after_ping_timeout_and_released(server):
    srv, backend, port = server
    s = socket.create_connection(("127.0.0.1", port))
    s.sendall(b"GET / HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
              b"Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n")
    s.recv(1000)
    wait_for(lambda: backend.closed, 10.0, 0.1)
    assert backend.closed and not srv.sessions
    s.close()


def test_stalled_reader_keeps_bounded_queue(server):
    srv, backend, port = server
    s = socket.create_connection(("127.0.0.1", port))
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.sendall(b"GET / HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
              b"Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n")
    s.recv(1000)
    sub = b'{"op":"subscribe","topic":"/loop"}'
    s.sendall(b"\x81" + bytes([0x80 | len(sub)]) + b"\x00\x00\x00\x00" + sub)
    ws = connect("ws://127.0.0.1:%d" % port, compression=None, max_size=None)
    payload = json.dumps({"op": "publish", "topic": "/loop", "msg": {"data": "z" * 20000}})
    for _ in range(600):  # 12 MB towards a reader that never reads
        ws.send(payload)

    def stalled():  # (sent is not handled: the server may still be working through the socket's backlog)
        return [sess for sess in list(srv.sessions.values()) if sess.out.dropped]

    assert wait_for(stalled, 10.0, 0.02), "no session dropped frames"
    assert len(stalled()[0].out) <= 50
    s.close()
    ws.close()
