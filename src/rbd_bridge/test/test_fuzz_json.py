"""Property-based fuzzing of the bridge's JSON handling (issue 10), no ROS master needed.

hypothesis drives the ROS-free modules with arbitrary JSON values, frames with wrong
types, unknown ops and fields, deep nesting, huge numbers, bad base64, arbitrary bytes
and CBOR. Properties: nothing raises out of ``Session.receive``; the session stays
usable; a denied topic/service never reaches the backend; conversion errors are only
``ConversionError``; every produced message serializes.

The number of examples per property is ``RBD_FUZZ_EXAMPLES`` (default 100, about 10 s
for the whole module); e.g. ``RBD_FUZZ_EXAMPLES=20000`` for a long run.
"""

import io
import json
import math
import os

import genpy
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_protocol import FakeBackend, Timers

from rbd_bridge.core import encoding
from rbd_bridge.core.outqueue import OutQueue
from rbd_bridge.core.security import Policy
from rbd_bridge.core.session import Session
from rbd_bridge.core.types import ConversionError
from rbd_bridge.ros.msgconv import dict_to_msg, get_message_class, msg_to_dict

EXAMPLES = int(os.environ.get("RBD_FUZZ_EXAMPLES", "100"))
FUZZ = settings(
    max_examples=EXAMPLES,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

OPS = [
    "advertise",
    "unadvertise",
    "publish",
    "subscribe",
    "unsubscribe",
    "call_service",
    "advertise_service",
    "unadvertise_service",
    "service_response",
    "fragment",
    "set_level",
    "status",
    "auth",
    "png",
    "send_action_goal",
    "",
]
FIELDS = [
    "op",
    "id",
    "topic",
    "type",
    "msg",
    "latch",
    "queue_size",
    "throttle_rate",
    "queue_length",
    "fragment_size",
    "compression",
    "service",
    "args",
    "values",
    "result",
    "timeout",
    "level",
    "data",
    "num",
    "total",
    "mac",
    "client",
    "dest",
    "rand",
    "t",
    "end",
]
# Topics and services that move the robot (denied by the RoboDog default) plus allowed ones
NAMES = [
    "/cmd_vel",
    "cmd_vel",
    "/cmd_vel ",
    "//cmd_vel",
    "/set_body_pose",
    "/rbd_pos_controller/set_position",
    "/rbd_controller/em_stop",
    "/rbd_gestrec/gesture",
    "/rbd_local/heartbeat",
    "/rbd_controller/state",
    "/rosapi/topics",
    "/rbd_gestrec/*",
    "*",
    "",
]
TYPES = ["std_msgs/String", "geometry_msgs/Twist", "rbd_msgs/SetBodyPose", "std_msgs/Header", "x", "a/b/c", ""]

scalars = (
    st.none()
    | st.booleans()
    | st.integers(min_value=-(2**70), max_value=2**70)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=20)
)
json_values = st.recursive(
    scalars,
    lambda children: st.lists(children, max_size=5) | st.dictionaries(st.text(max_size=8), children, max_size=5),
    max_leaves=25,
)
field_values = json_values | st.sampled_from(NAMES) | st.sampled_from(TYPES) | st.sampled_from(OPS)
frames = st.fixed_dictionaries(
    {"op": st.sampled_from(OPS) | json_values},
    optional={
        name: (st.sampled_from(NAMES) if name in ("topic", "service") else field_values)
        for name in FIELDS
        if name != "op"
    },
)

MOVING = ("/cmd_vel", "/set_body_pose", "/rbd_pos_controller/set_position")


def robodog_session():
    """A session under the RoboDog default allow-list, with a recording backend."""
    backend = FakeBackend()
    out = OutQueue(max_frames=200, max_bytes=1 << 20)
    timers = Timers()
    closed = []
    session = Session(1, backend, Policy(), out, timers.call_later, close=lambda c, r: closed.append(c))
    session.receive('{"op":"set_level","level":"info"}')  # every rejection is reported
    return session, backend, out, timers


def assert_no_motion(backend):
    for call in backend.calls:
        if call[0] in ("advertise", "publish", "subscribe", "call_service", "advertise_service"):
            name = call[2]
            assert not any(name == m or name.startswith(m + "/") for m in MOVING), call
            assert name in (
                "/rbd_gestrec/gesture",
                "/rbd_local/heartbeat",
                "/rbd_controller/state",
                "/rbd_controller/em_stop",
            ) or name.startswith("/rosapi/"), call


def assert_usable(session, backend, out):
    """After anything, a valid publish of an allowed topic still reaches the backend."""
    assert len(out) <= 200
    for status in _statuses(out):
        # an exception that escaped the op handlers is a bug even though the session survives
        assert status.get("op") != "status" or "internal error" not in status["msg"], status
    before = len(backend.calls)
    session.receive('{"op":"publish","topic":"/rbd_gestrec/gesture","msg":{"data":"wave"}}')
    assert backend.calls[before:] == [("publish", 1, "/rbd_gestrec/gesture", {"data": "wave"})]


def _fuzz_text(obj):
    try:
        return json.dumps(obj)
    except (ValueError, TypeError, RecursionError):
        return None


@settings(FUZZ, max_examples=max(10, EXAMPLES // 3))
@given(st.lists(frames, min_size=1, max_size=5))
def test_random_frames_never_break_the_session_nor_pass_the_allow_list(batch):
    session, backend, out, timers = robodog_session()
    for frame in batch:
        text = _fuzz_text(frame)
        if text is not None:
            session.receive(text)
        session.receive(encoding.cbor_dumps(frame) if _cbor_ok(frame) else b"\xff")
        timers.run_all()
    assert not session.closed
    assert_no_motion(backend)
    assert_usable(session, backend, out)


def _cbor_ok(frame):
    try:
        encoding.cbor_dumps(frame)
        return True
    except (ValueError, TypeError, OverflowError):
        return False


def _statuses(out):
    result = []
    while True:
        f = out.pop()
        if f is None:
            return result
        if isinstance(f, str):
            result.append(json.loads(f))


@FUZZ
@given(json_values)
def test_any_json_value_is_answered_not_raised(value):
    session, backend, out, _ = robodog_session()
    text = _fuzz_text(value)
    if text is not None:
        session.receive(text)
    assert not backend.calls
    assert_usable(session, backend, out)


@FUZZ
@given(st.binary(max_size=300) | st.text(max_size=300))
def test_arbitrary_bytes_and_text(data):
    session, backend, out, _ = robodog_session()
    session.receive(data)
    assert_no_motion(backend)
    assert_usable(session, backend, out)


@FUZZ
@given(st.integers(min_value=1, max_value=200000), st.sampled_from(["[", '{"a":', '[{"op":']))
def test_deep_nesting(depth, opener):
    session, backend, out, _ = robodog_session()
    session.receive(opener * depth)
    session.receive((opener * depth).encode())
    assert_usable(session, backend, out)


@FUZZ
@given(
    st.text(max_size=40),
    st.integers(min_value=-5, max_value=5),
    st.integers(min_value=-5, max_value=5),
    st.one_of(st.text(max_size=5), st.integers(), st.none()),
)
def test_random_fragments(data, num, total, frag_id):
    session, backend, out, _ = robodog_session()
    session.receive(json.dumps({"op": "fragment", "id": frag_id, "data": data, "num": num, "total": total}))
    assert_no_motion(backend)
    assert_usable(session, backend, out)


@FUZZ
@given(st.sampled_from(MOVING), st.integers(min_value=1, max_value=6), st.data())
def test_fragmented_denied_publish_stays_denied(topic, parts, data):
    """A denied publish split into fragments (any order) is still denied."""
    session, backend, out, _ = robodog_session()
    text = json.dumps({"op": "publish", "topic": topic, "msg": {"linear": {"x": 1.0}}})
    size = max(1, len(text) // parts)
    chunks = [text[i : i + size] for i in range(0, len(text), size)]
    order = data.draw(st.permutations(range(len(chunks))))
    for i in order:
        session.receive(json.dumps({"op": "fragment", "id": "f", "data": chunks[i], "num": i, "total": len(chunks)}))
    assert not backend.calls
    assert_usable(session, backend, out)


# ---------------------------------------------------------------- message conversion

CLASSES = [
    "std_msgs/String",
    "std_msgs/Header",
    "std_msgs/Int64",
    "std_msgs/UInt8MultiArray",
    "geometry_msgs/Twist",
    "geometry_msgs/PoseStamped",
    "sensor_msgs/Imu",
    "sensor_msgs/PointCloud2",
    "sensor_msgs/LaserScan",
    "rbd_msgs/SetBodyPoseRequest",
]


def _class(name):
    if name.endswith("Request"):
        from rbd_msgs.srv import SetBodyPose

        return SetBodyPose._request_class
    return get_message_class(name)


def _serializes(msg):
    buff = io.BytesIO()
    msg.serialize(buff)
    return buff.getvalue()


def _field_strategy():
    weird = st.sampled_from(
        [
            "not base64!",
            "AAA",
            "====",
            "QUJD",
            [0, 255, 256],
            [-1],
            [1.5],
            [True],
            2**64,
            -(2**63) - 1,
            2**63,
            1e308,
            -1e308,
            {"secs": 2**40, "nsecs": -1},
            {"secs": 1.5, "nsecs": 2},
            {"secs": "1", "nsecs": 0},
            [],
            {},
        ]
    )
    return json_values | weird


def _message_dicts():
    names = st.sampled_from(
        [
            "data",
            "header",
            "stamp",
            "seq",
            "frame_id",
            "linear",
            "angular",
            "x",
            "y",
            "z",
            "w",
            "pose",
            "position",
            "orientation",
            "orientation_covariance",
            "fields",
            "width",
            "height",
            "is_dense",
            "ranges",
            "layout",
            "dim",
            "secs",
            "nsecs",
            "unknown",
        ]
    )
    return st.recursive(
        st.dictionaries(names, _field_strategy(), max_size=6),
        lambda inner: st.dictionaries(names, inner | _field_strategy(), max_size=6),
        max_leaves=20,
    )


@settings(FUZZ, max_examples=max(10, EXAMPLES // 2))
@given(st.sampled_from(CLASSES), _message_dicts() | json_values)
def test_dict_to_msg_only_raises_conversion_error_and_results_serialize(type_name, data):
    cls = _class(type_name)
    try:
        msg, missing = dict_to_msg(cls, data, lambda: genpy.Time(1, 2))
    except ConversionError as exc:
        assert str(exc)
        return
    assert isinstance(missing, list)
    raw = _serializes(msg)
    # and back: what the bridge would send out is valid JSON with no NaN literal
    text = encoding.json_dumps(msg_to_dict(msg))
    json.loads(text, parse_constant=_no_constants)
    back = cls()
    back.deserialize(raw)


def _no_constants(name):
    raise AssertionError("non-JSON constant %s in output" % name)


@FUZZ
@given(st.floats(allow_nan=True, allow_infinity=True) | st.integers(min_value=-(2**80), max_value=2**80))
def test_numbers_in_float_int_and_time_fields(number):
    for type_name, data in (
        ("geometry_msgs/Twist", {"linear": {"x": number}}),
        ("std_msgs/Int64", {"data": number}),
        ("std_msgs/Header", {"seq": number, "stamp": {"secs": number, "nsecs": 0}}),
        ("std_msgs/UInt8MultiArray", {"data": [number]}),
    ):
        try:
            msg, _ = dict_to_msg(get_message_class(type_name), data)
        except ConversionError:
            continue
        _serializes(msg)
        if type_name == "std_msgs/Int64":
            assert msg.data == number  # 64-bit integers stay exact
        if type_name == "geometry_msgs/Twist" and isinstance(number, float) and math.isfinite(number):
            assert msg.linear.x == number


@FUZZ
@given(st.binary(max_size=200) | st.integers(min_value=1, max_value=100000).map(lambda n: b"\x81" * n + b"\x00"))
def test_cbor_loads_only_raises_decode_errors(data):
    try:
        encoding.cbor_loads(data)
    except (encoding.DecodeError, ValueError, TypeError, OverflowError):
        pass
    session, backend, out, _ = robodog_session()
    session.receive(data)
    assert session.errors <= 1 and not backend.calls
    assert_usable(session, backend, out)
