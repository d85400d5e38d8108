"""The bridge's publisher connection (``_DirectConnection``) against a real socket pair.

No master: a stand-in for rospy's TCPROS transport wraps one end of a socketpair; the
other end plays a ROS subscriber that reads (or does not).
"""

import socket
import threading
import time
import types

import pytest
from rospy.exceptions import TransportTerminated

from rbd_bridge.ros.fastpath import _DirectConnection


def _Cork():  # noqa: N802 (what FastPath keeps as its cork)
    return types.SimpleNamespace(thread=None, pending=[])


class FakeTransport:
    """What _DirectConnection uses of rospy's TCPROSTransport."""

    def __init__(self, sock):
        self.socket = sock
        self.done = False
        self.cleanup_cb = None
        self.stat_bytes = 0
        self.stat_num_msg = 0
        self.endpoint_id = "fake"

    def set_cleanup_callback(self, cb):
        self.cleanup_cb = cb

    def close(self):
        if not self.done:
            self.done = True
            try:  # as rospy: shutdown wakes a writer blocked in sendall
                self.socket.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
            self.socket.close()
            if self.cleanup_cb:
                self.cleanup_cb(self)


@pytest.fixture
def pair():
    a, b = socket.socketpair()
    a.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 8192)
    b.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 8192)
    yield a, b
    a.close()
    b.close()


def read_all(sock, count, timeout=10.0):
    sock.settimeout(timeout)
    data = b""
    while len(data) < count:
        chunk = sock.recv(65536)
        if not chunk:
            break
        data += chunk
    return data


def test_small_messages_go_out_at_once_without_a_thread():
    a, b = socket.socketpair()  # default buffers: 50 small messages fit
    conn = _DirectConnection(FakeTransport(a), queue_size=10)
    for i in range(50):
        assert conn.write_data(b"m%03d" % i)
    assert conn._thread is None  # every send completed in the caller
    assert read_all(b, 200) == b"".join(b"m%03d" % i for i in range(50))
    assert conn.endpoint_id == "fake"  # the rest is delegated to rospy's transport
    a.close()
    b.close()


def test_stuck_subscriber_never_blocks_the_caller_and_costs_bounded_memory(pair):
    a, b = pair
    conn = _DirectConnection(FakeTransport(a), queue_size=5)
    messages = [(b"%06d" % i) * 2000 for i in range(200)]  # 12 kB each, nobody reads
    t0 = time.monotonic()
    for m in messages:
        assert conn.write_data(m)
    assert time.monotonic() - t0 < 2.0  # the event loop would never have waited
    assert len(conn._backlog) <= 5 + 1
    assert conn.dropped > 150
    # once the subscriber reads, the kept messages arrive whole and in order, the newest last
    b.settimeout(1.0)
    data = b""
    try:
        while not data.endswith(messages[-1]):
            chunk = b.recv(65536)
            if not chunk:
                break
            data += chunk
    except socket.timeout:
        pass
    assert len(data) % 12000 == 0
    chunks = [data[k : k + 12000] for k in range(0, len(data), 12000)]
    assert all(c in messages for c in chunks)
    seqs = [int(c[:6]) for c in chunks]
    assert seqs == sorted(seqs) and seqs[-1] == 199 and len(seqs) < 200


def test_peer_gone_is_reported_not_raised_later_forever(pair):
    a, b = pair
    transport = FakeTransport(a)
    conn = _DirectConnection(transport, queue_size=5)
    b.close()
    with pytest.raises(TransportTerminated):
        for _ in range(100):
            conn.write_data(b"x" * 10000)
    assert transport.done
    with pytest.raises(TransportTerminated):
        conn.write_data(b"after")


def test_backlog_writer_stops_when_the_connection_closes(pair):
    a, b = pair
    transport = FakeTransport(a)
    conn = _DirectConnection(transport, queue_size=5)
    for _ in range(20):
        conn.write_data(b"y" * 10000)
    thread = conn._thread
    assert thread is not None
    transport.close()
    thread.join(5.0)
    assert not thread.is_alive()
    assert threading.active_count() < 50


class CountingSocket:
    """A socket wrapper counting send calls (one per syscall)."""

    def __init__(self, sock):
        self.sock = sock
        self.sends = 0

    def send(self, data, flags=0):
        self.sends += 1
        return self.sock.send(data, flags)

    def sendall(self, data):
        self.sends += 1
        return self.sock.sendall(data)

    def shutdown(self, how):
        self.sock.shutdown(how)

    def close(self):
        self.sock.close()


def test_writes_held_by_the_cork_leave_in_one_send_in_order():
    a, b = socket.socketpair()
    counting = CountingSocket(a)
    cork = _Cork()
    conn = _DirectConnection(FakeTransport(counting), queue_size=100, cork=cork)
    other = []  # a write from another thread is not held
    cork.thread = threading.get_ident()
    for i in range(30):
        assert conn.write_data(b"c%03d" % i)
    thread = threading.Thread(target=lambda: other.append(conn.write_data(b"T")))
    thread.start()
    thread.join(5)
    assert other == [True] and counting.sends == 1  # only the other thread's write went out
    assert cork.pending == [conn]
    cork.thread = None
    conn.uncork()
    assert counting.sends == 2
    assert read_all(b, 1 + 120) == b"T" + b"".join(b"c%03d" % i for i in range(30))
    conn.uncork()  # nothing held: nothing sent
    assert counting.sends == 2
    a.close()
    b.close()


def test_a_corked_burst_beyond_queue_size_leaves_in_one_send_then_message_by_message():
    # rospy keeps the newest queue_size messages of each read: a write never holds more
    # than the client's queue_size publishes, the rest of the burst goes one by one
    a, b = socket.socketpair()
    counting = CountingSocket(a)
    cork = _Cork()
    conn = _DirectConnection(FakeTransport(counting), queue_size=10, cork=cork)
    cork.thread = threading.get_ident()
    for i in range(30):
        assert conn.write_data(b"c%03d" % i)
    assert counting.sends == 1 + 20  # the first ten together when the eleventh came, then each
    cork.thread = None
    conn.uncork()
    assert counting.sends == 21  # nothing was left held
    assert read_all(b, 120) == b"".join(b"c%03d" % i for i in range(30))
    a.close()
    b.close()


def test_a_corked_write_to_a_closed_connection_raises_and_uncork_does_not():
    a, b = socket.socketpair()
    transport = FakeTransport(a)
    cork = _Cork()
    cork.thread = threading.get_ident()
    conn = _DirectConnection(transport, queue_size=10, cork=cork)
    assert conn.write_data(b"held")
    transport.close()
    with pytest.raises(TransportTerminated):
        conn.write_data(b"late")
    conn.uncork()  # the connection is gone: dropped quietly, rospy learns on its next write
    b.close()
