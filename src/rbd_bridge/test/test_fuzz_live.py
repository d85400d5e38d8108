"""Live fuzzing (issue 10): hypothesis-generated text and binary frames to a running bridge.

The bridge runs exactly as ``rbd_bridge.launch`` starts it (RoboDog allow-list). A
watcher node stands in for the robot: it subscribes ``/cmd_vel`` and ``/rbd_gestrec/gesture``
and serves ``/set_body_pose`` and ``/rbd_pos_controller/set_position``, logging everything
it gets to a file (ground truth). Per example: a burst of fuzzed frames on one connection,
then a ``/rosapi/get_time`` call that must be answered (no crash, no hang, the session stays
usable). At the end: nothing reached a denied topic or service, the bridge never registered
a publisher of ``/cmd_vel``, the bridge process is alive, and an allowed gesture sent the
same way does reach the watcher (so the watcher really listens).

Examples: ``RBD_FUZZ_LIVE_EXAMPLES`` (default 25; e.g. 2000 for a long run).
"""

import json
import os
import sys
import time

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rbd_bridge_testing import master_of, start_bridge, wait_for_service, wait_until
from test_fuzz_json import NAMES, OPS, TYPES, json_values
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from rbd_bridge.core import encoding
from rbd_testkit import RosEnv

EXAMPLES = int(os.environ.get("RBD_FUZZ_LIVE_EXAMPLES", "25"))

WATCHER = r"""
import sys, rospy
from geometry_msgs.msg import Twist
from std_msgs.msg import String
from rbd_msgs.srv import SetBodyPose, SetBodyPoseResponse, SetPosition, SetPositionResponse
log = open(sys.argv[1], "a", buffering=1)
rospy.init_node("fuzz_watcher")
rospy.Subscriber("/cmd_vel", Twist, lambda m: log.write("cmd_vel %s\n" % m.linear.x))
rospy.Subscriber("/rbd_gestrec/gesture", String, lambda m: log.write("gesture %s\n" % m.data))
def body(req):
    log.write("set_body_pose\n")
    return SetBodyPoseResponse()
def position(req):
    log.write("set_position\n")
    return SetPositionResponse()
rospy.Service("/set_body_pose", SetBodyPose, body)
rospy.Service("/rbd_pos_controller/set_position", SetPosition, position)
log.write("ready\n")
rospy.spin()
"""

TWIST = {"linear": {"x": 1.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 1.0}}


@pytest.fixture(scope="module")
def robot():
    """Master + watcher (stand-in robot) + the bridge as rbd_bridge.launch starts it."""
    env = RosEnv()
    try:
        log = os.path.join(env.home, "watcher.log")
        env.start([sys.executable, "-c", WATCHER, log])
        wait_for_service(env, "/rbd_pos_controller/set_position")
        port, proc = start_bridge(env, launch="rbd_bridge.launch")
        yield env, port, proc, log
    finally:
        env.close()


def events(log):
    with open(log) as f:
        return [line.split()[0] for line in f if line.strip()]


# frames aimed at what moves the robot, plus anything else
moving_frames = st.fixed_dictionaries(
    {
        "op": st.sampled_from(["advertise", "publish", "call_service", "advertise_service", "subscribe"]),
        "topic": st.sampled_from(["/cmd_vel", "cmd_vel", "/cmd_vel/", "/set_body_pose"]),
        "service": st.sampled_from(["/set_body_pose", "/rbd_pos_controller/set_position", "set_body_pose"]),
        "type": st.sampled_from(["geometry_msgs/Twist", "rbd_msgs/SetBodyPose", "rbd_msgs/SetPosition"]),
    },
    optional={"msg": st.just(TWIST) | json_values, "args": json_values, "id": json_values},
)
random_frames = st.fixed_dictionaries(
    {"op": st.sampled_from(OPS) | json_values},
    optional={
        "topic": st.sampled_from(NAMES) | json_values,
        "service": st.sampled_from(NAMES) | json_values,
        "type": st.sampled_from(TYPES) | json_values,
        "msg": json_values,
        "args": json_values,
        "id": json_values,
        "compression": st.sampled_from(["none", "png", "cbor", "cbor-raw", "zip"]) | json_values,
        "fragment_size": json_values,
        "throttle_rate": json_values,
        "queue_length": json_values,
        "data": json_values,
        "num": json_values,
        "total": json_values,
    },
)


def _as_text(frame):
    try:
        return json.dumps(frame)
    except (ValueError, TypeError, RecursionError):
        return "{"


def _as_binary(frame):
    try:
        return encoding.cbor_dumps(frame)
    except (ValueError, TypeError, OverflowError):
        return b"\xff\x00"


payloads = st.one_of(
    (moving_frames | random_frames).map(_as_text),
    (moving_frames | random_frames).map(_as_binary),
    json_values.map(_as_text),
    st.text(max_size=200),
    st.binary(max_size=200),
    st.integers(min_value=1, max_value=20000).map(lambda n: "[" * n),
)


def _alive_check(ws, tag):
    """A rosapi call on the same connection must be answered."""
    ws.send(json.dumps({"op": "call_service", "id": tag, "service": "/rosapi/get_time"}))
    deadline = time.monotonic() + 10.0
    while time.monotonic() < deadline:
        data = ws.recv(timeout=max(0.01, deadline - time.monotonic()))
        frame = json.loads(data) if isinstance(data, str) else encoding.cbor_loads(data)
        if isinstance(frame, dict) and frame.get("op") == "service_response" and frame.get("id") == tag:
            assert frame["result"] is True, frame
            return
    raise AssertionError("the session stopped answering")


def test_fuzzed_frames_no_crash_no_hang_no_motion(robot):
    env, port, proc, log = robot
    assert wait_until(lambda: "ready" in events(log), 10)
    counter = [0]

    @settings(
        max_examples=EXAMPLES,
        deadline=None,
        database=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.function_scoped_fixture],
    )
    @given(st.booleans(), st.lists(payloads, min_size=1, max_size=8))
    def one(opt_in, burst):
        counter[0] += 1
        ws = connect("ws://127.0.0.1:%d" % port, compression=None, max_size=None, open_timeout=15)
        try:
            if opt_in:
                ws.send('{"op":"set_level","level":"info"}')
            for payload in burst:
                ws.send(payload)
            _alive_check(ws, "alive-%d" % counter[0])
        except ConnectionClosed as exc:
            raise AssertionError("the bridge closed the session: %s" % exc) from None
        finally:
            ws.close()
        assert proc.poll() is None, "the bridge process died"

    one()
    # The watcher hears an allowed topic sent over the same bridge after the fuzz: the proof that
    # whatever the fuzz might have let through had its time to reach the watcher (and that the
    # check below can fail), instead of a sleep.
    ws = connect("ws://127.0.0.1:%d" % port, compression=None, open_timeout=15)
    try:
        ws.send(json.dumps({"op": "advertise", "topic": "/rbd_gestrec/gesture", "type": "std_msgs/String"}))

        def heard():
            ws.send(json.dumps({"op": "publish", "topic": "/rbd_gestrec/gesture", "msg": {"data": "wave"}}))
            return "gesture" in events(log)

        assert wait_until(heard, 20, 0.2), "the watcher never heard an allowed topic"
    finally:
        ws.close()
    # ground truth: nothing that moves the robot was published or called
    seen = events(log)
    assert "cmd_vel" not in seen and "set_body_pose" not in seen and "set_position" not in seen, seen
    pubs = dict(master_of(env).getSystemState()[0])
    assert "/cmd_vel" not in pubs or not [n for n in pubs["/cmd_vel"] if "bridge" in n]
    assert proc.poll() is None
