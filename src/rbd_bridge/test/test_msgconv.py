"""Message mapping as rosbridge does it (no ROS master needed)."""

import base64
import json
import math

import genpy
import pytest
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import CameraInfo, Image, PointCloud2, PointField
from std_msgs.msg import Duration, Float64, Header, Int64, String, UInt8MultiArray, UInt64

from rbd_bridge.core import encoding
from rbd_bridge.core.types import ConversionError, TypedArray, normalize_type
from rbd_bridge.ros.msgconv import dict_to_msg, get_message_class, get_service_class, message_typedefs, msg_to_dict

NOW = genpy.Time(1234, 5678)


def now():
    return NOW


def test_type_names_accept_ros2_spelling():
    assert normalize_type("std_msgs/msg/String") == "std_msgs/String"
    assert get_message_class("std_msgs/msg/String") is String
    assert get_service_class("std_srvs/srv/SetBool")._type == "std_srvs/SetBool"
    for bad in ("", "nope", "a/b/c/d", "std_msgs/Str ing", 5):
        with pytest.raises(ConversionError):
            normalize_type(bad)
    with pytest.raises(ConversionError):
        get_message_class("no_such_pkg/Thing")


def test_time_and_duration_are_secs_nsecs():
    h = Header(seq=3, stamp=genpy.Time(10, 20), frame_id="f")
    assert msg_to_dict(h) == {"seq": 3, "stamp": {"secs": 10, "nsecs": 20}, "frame_id": "f"}
    d = msg_to_dict(Duration(data=genpy.Duration(-1, 5)))
    assert d == {"data": {"secs": -1, "nsecs": 5}}
    msg, _ = dict_to_msg(Header, {"stamp": {"secs": 7, "nsecs": 9}}, now)
    assert msg.stamp == genpy.Time(7, 9)
    with pytest.raises(ConversionError, match="stamp"):
        dict_to_msg(Header, {"stamp": {"secs": 1, "bogus": 2}}, now)
    with pytest.raises(ConversionError):
        dict_to_msg(Header, {"stamp": "yesterday"}, now)


def test_uint8_arrays_are_base64_out_and_base64_or_list_in():
    raw = bytes(range(256))
    out = msg_to_dict(Image(data=raw))
    assert out["data"] == base64.b64encode(raw).decode()
    from_b64, _ = dict_to_msg(Image, {"data": base64.b64encode(b"\x01\x02\xff").decode()}, now)
    from_list, _ = dict_to_msg(Image, {"data": [1, 2, 255]}, now)
    assert bytes(from_b64.data) == bytes(from_list.data) == b"\x01\x02\xff"
    with pytest.raises(ConversionError, match="data"):
        dict_to_msg(Image, {"data": [1, 2, 256]}, now)
    with pytest.raises(ConversionError, match="base64"):
        dict_to_msg(Image, {"data": "not base64 !!"}, now)
    # UInt8MultiArray data is uint8[] too
    assert msg_to_dict(UInt8MultiArray(data=b"\x00\x10"))["data"] == "ABA="


def test_non_finite_floats_go_out_as_null_and_json_stays_valid():
    out = msg_to_dict(CameraInfo(D=[1.0, math.nan, math.inf, -math.inf]))
    assert out["D"] == [1.0, None, None, None]
    text = encoding.json_dumps(msg_to_dict(Float64(data=math.nan)))
    assert json.loads(text) == {"data": None}
    assert "NaN" not in text
    back, _ = dict_to_msg(Float64, {"data": None}, now)
    assert math.isnan(back.data)


def test_int_accepted_for_float_and_int64_kept_exact():
    msg, _ = dict_to_msg(Float64, {"data": 3}, now)
    assert msg.data == 3.0 and isinstance(msg.data, float)
    big = 2**63 - 1
    msg, _ = dict_to_msg(Int64, {"data": big}, now)
    assert msg.data == big
    assert json.loads(encoding.json_dumps(msg_to_dict(msg)))["data"] == big
    msg, _ = dict_to_msg(UInt64, {"data": 2**64 - 1}, now)
    assert msg_to_dict(msg)["data"] == 2**64 - 1
    with pytest.raises(ConversionError, match="out of range"):
        dict_to_msg(UInt64, {"data": -1}, now)
    with pytest.raises(ConversionError):
        dict_to_msg(Int64, {"data": 1.5}, now)
    with pytest.raises(ConversionError):
        dict_to_msg(String, {"data": 5}, now)


def test_missing_fields_take_defaults_and_are_reported():
    msg, missing = dict_to_msg(PointField, {"name": "x"}, now)
    assert msg.offset == 0 and msg.datatype == 0 and msg.count == 0
    assert sorted(missing) == ["count", "datatype", "offset"]
    msg, missing = dict_to_msg(String, None, now)
    assert msg.data == "" and missing == ["data"]


def test_unknown_fields_are_rejected_with_their_path():
    with pytest.raises(ConversionError, match="bogus"):
        dict_to_msg(String, {"data": "a", "bogus": 1}, now)
    with pytest.raises(ConversionError, match=r"pose\.position"):
        dict_to_msg(PoseStamped, {"pose": {"position": {"x": 1, "w": 2}}}, now)


def test_header_stamp_filled_when_header_or_stamp_missing():
    msg, _ = dict_to_msg(PoseStamped, {"pose": {"position": {"x": 1.5}}}, now)
    assert msg.header.stamp == NOW and msg.pose.position.x == 1.5
    msg, _ = dict_to_msg(PoseStamped, {"header": {"frame_id": "map"}}, now)
    assert msg.header.stamp == NOW and msg.header.frame_id == "map"
    msg, _ = dict_to_msg(PoseStamped, {"header": {"stamp": {"secs": 1, "nsecs": 2}}}, now)
    assert msg.header.stamp == genpy.Time(1, 2)


def test_fixed_arrays_checked_and_nested_arrays_converted():
    with pytest.raises(ConversionError, match="9"):
        dict_to_msg(CameraInfo, {"K": [1.0, 2.0]}, now)
    cloud, _ = dict_to_msg(
        PointCloud2,
        {"fields": [{"name": "x", "offset": 0, "datatype": 7, "count": 1}], "data": [1, 2, 3, 4], "width": 1},
        now,
    )
    out = msg_to_dict(cloud)
    assert out["fields"] == [{"name": "x", "offset": 0, "datatype": 7, "count": 1}]
    assert out["data"] == "AQIDBA=="
    assert out["header"]["stamp"] == {"secs": 1234, "nsecs": 5678}
    with pytest.raises(ConversionError, match=r"fields\[0\]"):
        dict_to_msg(PointCloud2, {"fields": [{"name": 3}]}, now)
    with pytest.raises(ConversionError):
        dict_to_msg(PointCloud2, {"fields": {"name": "x"}}, now)
    with pytest.raises(ConversionError):
        dict_to_msg(PointCloud2, "not an object", now)


def test_roundtrip_serializes_with_genpy():
    msg, _ = dict_to_msg(CameraInfo, {"D": [0.1, 2], "K": [1] * 9, "distortion_model": "plumb_bob"}, now)
    import io

    buff = io.BytesIO()
    msg.serialize(buff)  # the result must be a valid ROS message
    again = CameraInfo()
    again.deserialize(buff.getvalue())
    assert msg_to_dict(again) == msg_to_dict(msg)


def test_binary_mode_for_cbor_keeps_bytes_and_typed_arrays():
    out = msg_to_dict(CameraInfo(D=[1.0, math.nan]), binary=True)
    assert isinstance(out["D"], TypedArray) and out["D"].kind == "float64"
    assert isinstance(msg_to_dict(Image(data=b"\x01"), binary=True)["data"], bytes)


def test_message_typedefs_cover_nested_types():
    defs = message_typedefs(PoseStamped)
    types = [d["type"] for d in defs]
    assert types[0] == "geometry_msgs/PoseStamped"
    assert {"std_msgs/Header", "geometry_msgs/Pose", "geometry_msgs/Point", "geometry_msgs/Quaternion"} <= set(types)
    top = defs[0]
    assert top["fieldnames"] == ["header", "pose"]
    assert top["fieldarraylen"] == [-1, -1]
    cam = message_typedefs(CameraInfo)[0]
    assert cam["fieldarraylen"][cam["fieldnames"].index("K")] == 9
    assert cam["fieldarraylen"][cam["fieldnames"].index("D")] == 0
    field_defs = message_typedefs(PointField)[0]
    assert "FLOAT32" in field_defs["constnames"]
    assert field_defs["constvalues"][field_defs["constnames"].index("FLOAT32")] == "7"


def test_char_arrays_are_base64_like_uint8_arrays():
    # no message of Debian's ROS has a char[] field: generate one the way genpy does for .msg files
    import io

    from genpy.dynamic import generate_dynamic

    chars = generate_dynamic("rbd_test/CharArrays", "char[] data\nchar[3] fixed\nchar one\n")["rbd_test/CharArrays"]
    out = msg_to_dict(chars(data=b"ab\xff\x00", fixed=b"xyz", one=65))
    assert out == {"data": base64.b64encode(b"ab\xff\x00").decode(), "fixed": "eHl6", "one": 65}
    assert isinstance(msg_to_dict(chars(data=b"\x01"), binary=True)["data"], bytes)
    from_b64, _ = dict_to_msg(chars, {"data": "YWL/AA==", "fixed": "eHl6", "one": 66}, now)
    from_list, _ = dict_to_msg(chars, {"data": [97, 98, 255, 0], "fixed": [120, 121, 122], "one": 66}, now)
    assert bytes(from_b64.data) == bytes(from_list.data) == b"ab\xff\x00"
    assert bytes(from_b64.fixed) == bytes(from_list.fixed) == b"xyz"
    buff = io.BytesIO()
    from_list.serialize(buff)  # a valid ROS message
    again = chars()
    again.deserialize(buff.getvalue())
    assert msg_to_dict(again) == msg_to_dict(from_b64)
    with pytest.raises(ConversionError, match="fixed"):
        dict_to_msg(chars, {"fixed": [1, 2]}, now)  # char[3]
    with pytest.raises(ConversionError, match="data"):
        dict_to_msg(chars, {"data": [256]}, now)
    with pytest.raises(ConversionError, match="base64"):
        dict_to_msg(chars, {"data": "not base64 !!"}, now)
