"""CBOR/PNG/fragment encodings and the allow-list/auth helpers (ROS-free)."""

import json
import math
import struct

import pytest
from rbd_bridge_testing import png_text

from rbd_bridge.core import encoding
from rbd_bridge.core.security import (
    ROBODOG_PUBLISH,
    AuthError,
    Policy,
    check_mac,
    make_mac,
    parse_glob_list,
    policy_from_params,
)
from rbd_bridge.core.types import TypedArray

cbor2 = pytest.importorskip("cbor2")


def test_cbor_matches_an_independent_decoder():
    obj = {
        "op": "publish",
        "topic": "/t",
        "msg": {
            "i": -5,
            "big": 2**64 - 1,
            "f": 1.5,
            "s": "ü",
            "b": b"\x00\x01",
            "l": [True, False, None],
            "nan": math.nan,
        },
    }
    data = encoding.cbor_dumps(obj)
    decoded = cbor2.loads(data)
    assert decoded["msg"]["big"] == 2**64 - 1 and decoded["msg"]["b"] == b"\x00\x01"
    assert math.isnan(decoded["msg"]["nan"])
    ours = encoding.cbor_loads(data)
    assert ours["msg"]["s"] == "ü" and ours["msg"]["l"] == [True, False, None]
    assert encoding.cbor_loads(cbor2.dumps({"op": "x", "v": [1, -2, 3.25]})) == {"op": "x", "v": [1, -2, 3.25]}


def test_cbor_typed_arrays_use_little_endian_tags():
    data = encoding.cbor_dumps({"a": TypedArray("float32", [1.0, 2.0]), "b": TypedArray("uint16", [1, 2])})
    decoded = cbor2.loads(data)
    assert decoded["a"].tag == 85 and decoded["a"].value == struct.pack("<2f", 1.0, 2.0)
    assert decoded["b"].tag == 69
    assert encoding.cbor_loads(data) == {"a": [1.0, 2.0], "b": [1, 2]}


@pytest.mark.parametrize(
    "garbage", [b"", b"\xff", b"\x5b\xff\xff\xff\xff\xff\xff\xff\xff", b"\xa1\x01", b"\x9f", b"\x81" * 100, b"\x82\x01"]
)
def test_cbor_decoder_rejects_garbage(garbage):
    with pytest.raises(encoding.DecodeError):
        encoding.cbor_loads(garbage)


def test_png_roundtrip_and_fragments():
    text = json.dumps({"op": "publish", "topic": "/t", "msg": {"data": "x" * 1000}})
    decoded = png_text(encoding.png_encode(text))
    assert decoded.rstrip("\n") == text and json.loads(decoded) == json.loads(text)  # newline padding
    parts = encoding.fragment(text, 100, "id1")
    assert len(parts) == (len(text) + 99) // 100
    assert "".join(json.loads(p)["data"] for p in parts) == text
    assert [json.loads(p)["total"] for p in encoding.fragment("short", 100, "x")] == [1]
    assert json.loads(encoding.json_dumps({"v": [math.inf, 1.0]})) == {"v": [None, 1.0]}


def test_glob_lists_parse_rosbridge_forms():
    assert parse_glob_list("[*]") == ("*",)
    assert parse_glob_list("['/a', '/b/*']") == ("/a", "/b/*")
    assert parse_glob_list("[/a, /b]") == ("/a", "/b")
    assert parse_glob_list("[]") == ()
    assert parse_glob_list("") is None and parse_glob_list(None) is None
    assert parse_glob_list(["/x"]) == ("/x",)


def test_robodog_default_policy_denies_motion():
    policy = policy_from_params(lambda name, default: default)
    for topic in ROBODOG_PUBLISH:
        assert policy.may_publish(topic)
    for topic in ("/cmd_vel", "/rbd_controller/estop", "/rbd_sim/ground_truth"):
        assert not policy.may_publish(topic)
    assert policy.may_subscribe("/rbd_controller/state") and not policy.may_subscribe("/cmd_vel")
    assert policy.may_call("/rbd_controller/em_stop") and policy.may_call("/rosapi/topics")
    for service in ("/set_body_pose", "/rbd_pos_controller/set_position", "/rbd_controller/collision"):
        assert not policy.may_call(service)
    assert not policy.may_read_param("/anything") and not policy.may_write_param("/anything")


def test_topics_glob_opens_both_directions_and_direction_overrides():
    values = {"topics_glob": "[*]", "subscribe_topics_glob": "[/only]", "params_glob": "[/p/*]"}
    policy = policy_from_params(lambda name, default: values.get(name, default))
    assert policy.may_publish("/cmd_vel")
    assert policy.may_subscribe("/only") and not policy.may_subscribe("/other")
    assert isinstance(policy, Policy)


def test_launch_habits_of_rosbridge():
    # rosbridge_websocket adds /rosapi/* to a given services_glob, and rosapi writes the
    # parameters of a given params_glob; RoboDog's default has no parameters at all
    def policy(**values):
        return policy_from_params(lambda name, default: values.get(name, default))

    given = policy(services_glob="[/echo/*]", params_glob="[/p/*]")
    assert given.may_call("/echo/x") and given.may_call("/rosapi/topics") and not given.may_call("/other")
    assert given.may_read_param("/p/x") and given.may_write_param("/p/x")
    assert not given.may_read_param("/q") and not given.may_write_param("/q")
    read_only = policy(params_glob="[/p/*]", params_writable="false")
    assert read_only.may_read_param("/p/x") and not read_only.may_write_param("/p/x")
    assert policy(params_glob="[/p/*]", params_writable=False).may_write_param("/p/x") is False
    closed = policy(services_glob="[]")
    assert not closed.may_call("/rosapi/topics")  # an empty list stays empty, as in rosbridge
    robodog = policy()
    assert robodog.may_call("/rosapi/topics") and robodog.may_call("/rbd_controller/em_stop")
    assert not robodog.may_read_param("/run_id") and not robodog.may_write_param("/run_id")


def test_mac_check_like_rosauth():
    secret = "abcdefghijklmnop"
    mac = make_mac(secret, "c", "d", "r", 100, "user", 200)
    frame = {"mac": mac, "client": "c", "dest": "d", "rand": "r", "t": 100, "level": "user", "end": 200}
    check_mac(secret, frame, now=103.0)
    check_mac(secret, dict(frame, t={"secs": 100, "nsecs": 5}), now=100.0)
    with pytest.raises(AuthError, match="MAC"):
        check_mac("another secret!!", frame, now=100.0)
    with pytest.raises(AuthError, match="time"):
        check_mac(secret, frame, now=110.0)
    with pytest.raises(AuthError, match="end"):
        check_mac(secret, dict(frame, end=102, mac=make_mac(secret, "c", "d", "r", 100, "user", 102)), now=103.0)
    with pytest.raises(AuthError, match="string"):
        check_mac(secret, dict(frame, client=5), now=100.0)
