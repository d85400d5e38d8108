"""Helpers for rbd_bridge integration tests (imported by conftest.py and the test modules).

The generic ones (ports, the private master, waiting) come from the test kit, rbd_testkit.
"""

import base64
import functools
import json
import os
import struct
import subprocess
import sys
import tempfile
import time
import xmlrpc.client
import zlib

import rosgraph
from websockets.sync.client import connect

from rbd_bridge.core import encoding
from rbd_testkit import free_port, wait_for, wait_for_port

PKG = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ROOT = os.path.dirname(os.path.dirname(PKG))
ECHO = os.path.join(PKG, "bench", "echo_node")
TEST = os.path.join(PKG, "test")
PROBE = os.path.join(TEST, "ros_probe.py")
FIBONACCI = os.path.join(TEST, "fibonacci_server.py")


def master_of(env):
    return rosgraph.Master("/rbd_bridge_test", master_uri=env.env["ROS_MASTER_URI"])


# A predicate that raises (a rosapi call while the bridge comes up) counts as "not yet".
wait_until = functools.partial(wait_for, ignore=(Exception,))


def server_outbound(env, node):
    """Topics on which ``node`` has a connected subscriber (the node's own getBusInfo)."""
    code, _, info = xmlrpc.client.ServerProxy(master_of(env).lookupNode(node)).getBusInfo("/rbd_bridge_test")
    # rospy's rows: [id, destination, direction, transport, topic, connected, ...]
    return {row[4] for row in info if code == 1 and row[2] == "o" and (len(row) < 6 or row[5])}


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


def start_probe(env, name, subs=(), pubs=(), defer=None):
    """Start test/ros_probe.py as node ``name`` (plain rospy subscribers/publishers: the ROS-side truth)."""
    cmd = [sys.executable, PROBE, "__name:=%s" % name] + (["--defer", str(defer)] if defer is not None else [])
    for spec in subs:
        cmd += ["--sub", spec]
    for spec in pubs:
        cmd += ["--pub", spec]
    proc = env.start(cmd)
    wait_for_service(env, "/%s/report" % name)
    return proc


def probe_call(env, name, service="report"):
    """Call a probe's ``~report`` (parsed JSON) or ``~publish`` from this process (no init_node needed)."""
    import rospy
    from std_srvs.srv import Trigger

    os.environ["ROS_MASTER_URI"] = env.env["ROS_MASTER_URI"]
    reply = rospy.ServiceProxy("/%s/%s" % (name, service), Trigger)()
    return json.loads(reply.message) if service == "report" else reply.message


# The ROS tutorials' types that rosbridge's and the clients' own tests use; Debian has
# neither actionlib_tutorials nor rospy_tutorials, so the tests generate them (Debian's
# genaction.py and genpy) into a directory put on PYTHONPATH.
_FIBONACCI = "int32 order\n---\nint32[] sequence\n---\nint32[] sequence\n"
_TUTORIAL_ACTIONS = {"actionlib_tutorials": {"Fibonacci": _FIBONACCI}}
_TUTORIAL_SERVICES = {"rospy_tutorials": {"AddTwoInts": "int64 a\nint64 b\n---\nint64 sum\n"}}
_MSG_PATHS = ["-Istd_msgs:/usr/share/std_msgs/msg", "-Iactionlib_msgs:/usr/share/actionlib_msgs/msg"]


def make_tutorial_types(dest=None):
    """Generate actionlib_tutorials/Fibonacci* and rospy_tutorials/AddTwoInts Python modules; return the path."""
    dest = dest or tempfile.mkdtemp(prefix="rbd-bridge-types.")
    py = "/usr/bin/python3"

    def run(*cmd):
        subprocess.run([py] + list(cmd), check=True, stdout=subprocess.DEVNULL, cwd=dest)

    for pkg, actions in _TUTORIAL_ACTIONS.items():
        spec_dir, msg_dir = os.path.join(dest, "spec", pkg, "action"), os.path.join(dest, "spec", pkg, "msg")
        os.makedirs(spec_dir)
        for name, text in actions.items():
            path = os.path.join(spec_dir, name + ".action")
            with open(path, "w") as f:
                f.write(text)
            run("/usr/lib/actionlib_msgs/genaction.py", "-o", msg_dir, path)
        out = os.path.join(dest, pkg, "msg")
        msgs = sorted(os.path.join(msg_dir, m) for m in os.listdir(msg_dir))
        run("/usr/lib/genpy/genmsg_py.py", "-p", pkg, "-o", out, "-I%s:%s" % (pkg, msg_dir), *(_MSG_PATHS + msgs))
        run("/usr/lib/genpy/genmsg_py.py", "--initpy", "-p", pkg, "-o", out)
        open(os.path.join(dest, pkg, "__init__.py"), "w").close()
    for pkg, services in _TUTORIAL_SERVICES.items():
        spec_dir = os.path.join(dest, "spec", pkg, "srv")
        os.makedirs(spec_dir)
        out = os.path.join(dest, pkg, "srv")
        for name, text in services.items():
            path = os.path.join(spec_dir, name + ".srv")
            with open(path, "w") as f:
                f.write(text)
            run("/usr/lib/genpy/gensrv_py.py", "-p", pkg, "-o", out, _MSG_PATHS[0], path)
        run("/usr/lib/genpy/gensrv_py.py", "--initpy", "-p", pkg, "-o", out)
        open(os.path.join(dest, pkg, "__init__.py"), "w").close()
    return dest


def use_tutorial_types(env, path):
    """Let env's processes (started from now on) and this process import the generated types."""
    env.env["PYTHONPATH"] = path + os.pathsep + env.env.get("PYTHONPATH", "")
    if path not in sys.path:
        sys.path.insert(0, path)


def png_text(data):
    """The text a client reads out of a ``png`` op's data, decoded as the clients do (nothing stripped).

    base64 -> PNG chunks -> inflated IDAT -> rows without their filter byte (rosbridge uses
    filter 0 only) -> UTF-8. The padding stays: clients hand the whole text to their JSON
    parser, where newlines are whitespace and NUL bytes an error.
    """
    png = base64.b64decode(data)
    assert png[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width, channels = 8, [], 0, 0
    while pos < len(png):
        (length,) = struct.unpack(">I", png[pos : pos + 4])
        kind, payload = png[pos + 4 : pos + 8], png[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            width, _, depth, color = struct.unpack(">IIBB", payload[:10])
            assert depth == 8
            channels = {0: 1, 2: 3, 6: 4}[color]
        elif kind == b"IDAT":
            idat.append(payload)
        pos += 12 + length
    rows = zlib.decompress(b"".join(idat))
    stride = width * channels + 1
    assert all(rows[i] == 0 for i in range(0, len(rows), stride)), "filter type 0 expected"
    return b"".join(rows[i + 1 : i + stride] for i in range(0, len(rows), stride)).decode("utf-8")


# Everything allowed; a short publisher linger, so that tests of "unadvertise ends the topic" wait little.
LINGER = 0.5
OPEN = {
    "topics_glob": "[*]",
    "services_glob": "[*]",
    "params_glob": "[*]",
    "params_writable": "true",
    "publisher_linger": LINGER,
}


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
