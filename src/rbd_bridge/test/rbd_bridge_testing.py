"""Helpers for rbd_bridge integration tests (imported by conftest.py and the test modules).

The generic ones (ports, the private master, waiting) come from the test kit, rbd_testkit.
"""

import functools
import json
import os
import sys
import time

import rosgraph
from websockets.sync.client import connect

from rbd_bridge import encoding
from rbd_testkit import free_port, wait_for, wait_for_port

PKG = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ROOT = os.path.dirname(os.path.dirname(PKG))
ECHO = os.path.join(PKG, "bench", "echo_node")


def master_of(env):
    return rosgraph.Master("/rbd_bridge_test", master_uri=env.env["ROS_MASTER_URI"])


# A predicate that raises (a rosapi call while the bridge comes up) counts as "not yet".
wait_until = functools.partial(wait_for, ignore=(Exception,))


def wait_for_service(env, name, timeout=20.0):
    master = master_of(env)
    assert wait_until(lambda: master.lookupService(name), timeout), "service %s never appeared" % name


def start_echo(env, ns=None, tick_rate=0.0):
    cmd = [sys.executable, ECHO, "_tick_rate:=%s" % tick_rate]
    if ns:
        cmd.append("__ns:=%s" % ns)
    proc = env.start(cmd)
    wait_for_service(env, (ns or "") + "/echo/slow")
    return proc


def start_bridge(env, launch="bridge.launch", **args):
    port = free_port()
    cmd = ["roslaunch", "rbd_bridge", launch, "port:=%d" % port, "address:=127.0.0.1"]
    cmd += ["%s:=%s" % (k, v) for k, v in args.items()]
    proc = env.start(cmd)
    wait_for_port(port, timeout=40.0)
    return port, proc


OPEN = {"topics_glob": "[*]", "services_glob": "[*]", "params_glob": "[*]", "params_writable": "true"}


class WsClient:
    """A raw WebSocket client (websockets, sync): JSON or CBOR frames in, dicts out."""

    def __init__(self, url, **kwargs):
        self.ws = connect(url, compression=None, max_size=None, open_timeout=15, **kwargs)

    def send(self, frame):
        self.ws.send(frame if isinstance(frame, (str, bytes)) else json.dumps(frame))

    def recv(self, timeout=10.0):
        data = self.ws.recv(timeout=timeout)
        return json.loads(data) if isinstance(data, str) else encoding.cbor_loads(data)

    def recv_until(self, predicate, timeout=10.0):
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("no matching frame")
            frame = self.recv(left)
            if predicate(frame):
                return frame

    def drain(self, duration=0.3):
        """Collect every frame arriving within duration seconds."""
        frames = []
        deadline = time.monotonic() + duration
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                return frames
            try:
                frames.append(self.recv(left))
            except TimeoutError:
                return frames

    def close(self):
        self.ws.close()
