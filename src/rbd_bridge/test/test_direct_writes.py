"""Direct writes from another thread (``_Connection.try_direct``) racing the event loop's writes.

No ROS: the transport with a fake backend (``test_server``), a thread standing in for a
rospy receive thread. Every frame must arrive whole and each writer's frames in order;
a client that does not read makes direct writes decline (never wait, never queue more).
"""

import json
import socket
import threading
import time

from test_server import server  # noqa: F401  (fixture)
from websockets.sync.client import connect

from rbd_bridge.core.fanout import TopicMessage
from rbd_testkit import wait_for


def _wait_session(srv, timeout=5.0):
    def subscribed():
        sessions = list(srv.sessions.values())
        return sessions[0] if sessions and sessions[0].subs else None

    return wait_for(subscribed, timeout, 0.01, what="a subscribed session")


def test_direct_and_loop_writes_interleave_as_whole_frames_in_order(server):  # noqa: F811
    srv, _, port = server
    ws = connect("ws://127.0.0.1:%d" % port, compression=None, max_size=None)
    ws.send(json.dumps({"op": "subscribe", "topic": "/loop"}))
    session = _wait_session(srv)
    assert session.direct is not None and session.direct_compression("/loop") == "none"
    n = 400
    taken = []
    lock = threading.Lock()
    pending = [0]  # as ros_backend: no direct write while older frames wait for the loop

    def deliver(message):
        session.deliver("/loop", message)
        with lock:
            pending[0] -= 1

    def ros_thread():
        for i in range(n):
            text = "d%d-" % i + "x" * (i % 7 * 3000)  # some frames bigger than a socket write
            message = TopicMessage("/loop", lambda binary, text=text: {"data": text})
            with lock:
                if pending[0] == 0 and session.direct(message, "none"):
                    taken.append(i)
                    continue
                pending[0] += 1
            srv.loop.call_soon_threadsafe(deliver, message)

    thread = threading.Thread(target=ros_thread)
    thread.start()
    for i in range(n):  # the loop publishes at the same time
        ws.send(json.dumps({"op": "publish", "topic": "/loop", "msg": {"data": "l%d" % i}}))
    thread.join(20)
    direct, loop = [], []
    while len(direct) + len(loop) < 2 * n:
        frame = json.loads(ws.recv(timeout=10))  # raises if a frame is torn
        data = frame["msg"]["data"]
        (direct if data[0] == "d" else loop).append(int(data[1:].split("-")[0]))
    ws.close()
    assert loop == list(range(n))
    assert direct == list(range(n))
    assert taken  # the direct path was really used


def test_stalled_client_makes_direct_writes_decline(server):  # noqa: F811
    srv, _, port = server
    sock = socket.create_connection(("127.0.0.1", port))
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    sock.sendall(
        b"GET / HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        b"Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
    )
    sub = b'{"op":"subscribe","topic":"/loop"}'
    sock.sendall(b"\x81" + bytes([0x80 | len(sub)]) + b"\x00\x00\x00\x00" + sub)
    session = _wait_session(srv)
    big = "z" * 100000
    results = []
    t0 = time.monotonic()
    for _ in range(200):  # 20 MB offered to a client that never reads
        message = TopicMessage("/loop", lambda binary: {"data": big})
        results.append(session.direct(message, "none"))
    assert time.monotonic() - t0 < 5.0  # never waited for the client
    assert results.count(False) > 150  # declined once the socket was full
    conn = srv._connections[session.client_id]
    assert conn.head is None or len(conn.head) <= 100100  # at most one partial frame kept
    sock.close()
