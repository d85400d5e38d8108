"""Fixtures for rbd_bridge integration tests: a private master, the echo peer, real bridges.

One master + echo node + bridge per test module (starting them costs seconds); every
process is stopped by PID by the test kit's RosEnv.
"""

import os
import sys
import types

import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from rbd_bridge_testing import OPEN, make_tutorial_types, start_bridge, start_echo, use_tutorial_types  # noqa: E402

from rbd_testkit import RosEnv  # noqa: E402

# roslibpy's rosapi helpers (get_topics, get_time, set_param, ...) give up after 3 s by default;
# under make test's load a niced test process can stall longer than that. The client's own
# setting, for every test here (what a test asserts of an answer does not change).
ROSAPI_TIMEOUT = 30.0


def pytest_configure(config):
    try:
        import roslibpy
    except ImportError:  # the tests that need it say so themselves
        return
    roslibpy.set_rosapi_timeout(ROSAPI_TIMEOUT)


@pytest.fixture(scope="session")
def tutorial_types(tmp_path_factory):
    """actionlib_tutorials/Fibonacci* and rospy_tutorials/AddTwoInts, generated once per session."""
    return make_tutorial_types(str(tmp_path_factory.mktemp("tutorial_types")))


@pytest.fixture(scope="module")
def open_bridge(tutorial_types):
    """Master + echo peer (50 Hz tick) + a bridge with everything allowed (tutorial types importable)."""
    env = RosEnv()
    try:
        use_tutorial_types(env, tutorial_types)
        start_echo(env, tick_rate=50.0)
        port, proc = start_bridge(env, **OPEN)
        yield types.SimpleNamespace(env=env, port=port, proc=proc, url="ws://127.0.0.1:%d" % port)
    finally:
        env.close()


@pytest.fixture
def roslibpy_client(open_bridge):
    """A connected roslibpy client (asyncio transport), closed after the test."""
    import roslibpy

    clients = []

    def connect(port=None):
        ros = roslibpy.Ros("127.0.0.1", port or open_bridge.port, transport="asyncio")
        ros.run(timeout=15)
        clients.append(ros)
        return ros

    yield connect
    for ros in clients:
        try:
            ros.close()
        except Exception:
            pass
