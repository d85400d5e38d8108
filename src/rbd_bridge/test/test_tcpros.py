"""The event-loop TCPROS reader (``rbd_bridge.tcpros``) without ROS: framing and a real socket pair."""

import asyncio
import random
import socket
import struct
import threading

import pytest

from rbd_bridge.core.tcpros import FramingError, LoopReader, TcprosFramer


def _stream(payloads):
    return b"".join(struct.pack("<I", len(p)) + p for p in payloads)


def test_framer_returns_every_payload_whatever_the_split():
    rng = random.Random(7)
    payloads = [bytes([i % 251]) * size for i, size in enumerate([0, 1, 3, 4, 5, 100, 70000, 2, 300000, 0, 9])]
    stream = _stream(payloads)
    for _ in range(30):
        framer = TcprosFramer()
        out = []
        pos = 0
        while pos < len(stream):
            step = rng.choice([1, 2, 3, 4, 5, 17, 4096, 65536, 400000])
            out += framer.feed(memoryview(stream)[pos : pos + step])
            pos += step
        assert out == payloads
        assert framer.buffered == 0


def test_framer_keeps_an_incomplete_message_until_its_last_byte():
    framer = TcprosFramer()
    stream = _stream([b"abc", b"defgh"])
    assert framer.feed(stream[:-1]) == [b"abc"]
    assert framer.buffered == 4 + 4
    assert framer.feed(stream[-1:]) == [b"defgh"]
    assert framer.buffered == 0


def test_framer_rejects_an_absurd_length():
    framer = TcprosFramer(max_message=1000)
    with pytest.raises(FramingError):
        framer.feed(struct.pack("<I", 1001) + b"x")


class _Loop:
    """An asyncio loop running in a thread; run(fn) executes fn on it and returns its result."""

    def __init__(self):
        self.loop = asyncio.new_event_loop()
        self.thread = threading.Thread(target=self.loop.run_forever, daemon=True)
        self.thread.start()

    def run(self, fn, *args):
        async def call():
            return fn(*args)

        return asyncio.run_coroutine_threadsafe(call(), self.loop).result(5)

    def close(self):
        self.loop.call_soon_threadsafe(self.loop.stop)
        self.thread.join(5)
        self.loop.close()


@pytest.fixture
def loop():
    runner = _Loop()
    yield runner
    runner.close()


def _reader(loop, sock):
    got = []
    closed = []
    done = threading.Event()
    ended = threading.Event()

    def on_messages(payloads):
        assert threading.current_thread() is loop.thread  # read in the loop, not elsewhere
        got.extend(payloads)
        done.set()

    def on_close(error):
        closed.append(error)
        ended.set()

    reader = LoopReader(loop.loop, sock, on_messages, on_close)
    return reader, got, closed, done, ended


def test_loop_reader_delivers_in_order_then_reports_eof(loop):
    a, b = socket.socketpair()
    reader, got, closed, _, ended = _reader(loop, b)
    payloads = [b"m%05d" % i * (1 + i % 50) for i in range(2000)] + [b"z" * 1000000]
    loop.run(reader.start)
    loop.run(reader.feed, _stream([b"leftover"]))  # bytes read during the handshake come first
    a.sendall(_stream(payloads))
    a.close()
    assert ended.wait(10)
    assert got == [b"leftover"] + payloads
    assert closed == [None]
    assert reader.closed and b.fileno() == -1  # the reader closed its socket
    assert reader.messages == len(payloads) + 1


def test_loop_reader_stop_is_idempotent_and_ends_reading(loop):
    a, b = socket.socketpair()
    reader, got, closed, done, _ = _reader(loop, b)
    loop.run(reader.start)
    a.sendall(_stream([b"one"]))
    assert done.wait(5)
    loop.run(reader.stop)
    loop.run(reader.stop)
    assert closed == [None]
    with pytest.raises(OSError):  # peer sees the close
        for _ in range(10):
            a.sendall(b"x" * 65536)
    assert got == [b"one"]
    a.close()


def test_loop_reader_closes_on_a_corrupt_stream(loop):
    a, b = socket.socketpair()
    reader, got, closed, _, ended = _reader(loop, b)
    reader.framer.max_message = 100
    loop.run(reader.start)
    a.sendall(_stream([b"ok"]) + struct.pack("<I", 5000) + b"garbage")
    assert ended.wait(5)
    assert got == [b"ok"]
    assert isinstance(closed[0], FramingError)
    a.close()


def test_a_shutdown_of_the_original_socket_ends_a_reader_on_its_duplicate(loop):
    """As in the bridge: rospy keeps its socket object; its close() (shutdown) ends our dup."""
    a, b = socket.socketpair()
    dup = b.dup()
    reader, _, closed, _, ended = _reader(loop, dup)
    loop.run(reader.start)
    b.shutdown(socket.SHUT_RDWR)
    b.close()
    assert ended.wait(5)
    assert closed == [None]
    a.close()
