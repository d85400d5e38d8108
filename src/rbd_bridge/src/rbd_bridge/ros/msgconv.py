"""ROS message <-> JSON-ready dict conversion with rosbridge v2 semantics (README, Message mapping).

Needs only genpy message classes (no master); converters are compiled once per class and cached.
"""

import base64
import binascii
import functools
import math
import time
import types
from typing import Any, Callable, Optional

import genpy
import roslib.message
from genmsg.msgs import parse_type

from rbd_bridge.core.types import ConversionError, TypedArray, normalize_type

__all__ = ["get_message_class", "get_service_class", "msg_to_dict", "dict_to_msg", "message_typedefs"]

_INT_RANGES = {"byte": (-(2**7), 2**7 - 1), "char": (0, 2**8 - 1)}  # ROS 1: byte is int8, char is uint8
for _bits in (8, 16, 32, 64):
    _INT_RANGES["int%d" % _bits] = (-(2 ** (_bits - 1)), 2 ** (_bits - 1) - 1)
    _INT_RANGES["uint%d" % _bits] = (0, 2**_bits - 1)
_FLOATS = ("float32", "float64")
_BINARY = ("uint8", "char")


def _load(kind: str, type_name: str) -> Any:  # roslib caches the classes it found
    name = normalize_type(type_name)
    load = roslib.message.get_message_class if kind == "message" else roslib.message.get_service_class
    try:
        cls = load(name)
    except Exception as exc:  # roslib raises many kinds on bad packages
        raise ConversionError("cannot load %s type %s: %s" % (kind, name, exc)) from None
    if cls is None:
        raise ConversionError("unknown %s type %s" % (kind, name))
    return cls


def get_message_class(type_name: str) -> Any:
    """Load a message class by name (e.g. ``std_msgs/String``); raises ConversionError."""
    return _load("message", type_name)


def get_service_class(type_name: str) -> Any:
    """Load a service class (with ``_request_class`` / ``_response_class``); raises ConversionError."""
    return _load("service", type_name)


def _finite(value: Any) -> Any:
    # inf - inf and nan - nan are nan; finite - finite is 0.0
    return value if value - value == 0 else None


def _time_out(value: Any) -> Any:
    return {"secs": value.secs, "nsecs": value.nsecs}


def _b64(value: Any) -> Any:
    return base64.b64encode(bytes(value)).decode("ascii")


@functools.lru_cache(maxsize=None)
def _compile_out(cls: Any, binary: bool) -> Any:
    plan = []
    for name, slot_type in zip(cls.__slots__, cls._slot_types):
        base, is_array, _ = parse_type(slot_type)
        if base in _BINARY and is_array:
            conv = bytes if binary else _b64
        elif binary and is_array and (base in _FLOATS or base in _INT_RANGES):
            conv = functools.partial(TypedArray, base)
        elif base in _FLOATS:
            conv = _float_list if is_array else None if binary else _finite
        elif base in ("time", "duration"):
            conv = (lambda v: [_time_out(x) for x in v]) if is_array else _time_out
        elif base in _INT_RANGES or base in ("bool", "string"):
            conv = list if is_array else None
        else:
            conv = _nested_out(_compile_out(get_message_class(base), binary), is_array)
        plan.append((name, conv))
    return tuple(plan)


def _float_list(values: Any) -> Any:
    return [v if v - v == 0 else None for v in values]  # (as _finite)


def _nested_out(plan: Any, is_array: bool) -> Any:
    if is_array:
        return lambda v: [_convert_out(plan, x) for x in v]
    return functools.partial(_convert_out, plan)


def _convert_out(plan: Any, msg: Any) -> Any:
    out = {}
    for name, conv in plan:
        value = getattr(msg, name)
        out[name] = value if conv is None else conv(value)
    return out


def msg_to_dict(msg: Any, binary: bool = False) -> Any:
    """A genpy message as a JSON-ready dict (rosbridge mapping).

    With binary (for CBOR) byte arrays stay ``bytes``, numeric arrays become
    :class:`TypedArray` s and floats keep NaN/Inf.
    """
    return _convert_out(_compile_out(type(msg), binary), msg)


def _is_int(value: Any) -> Any:
    return isinstance(value, int) and not isinstance(value, bool)


def _int_in(base: str) -> Any:
    low, high = _INT_RANGES[base]

    def conv(value: Any, path: str, ctx: Any) -> Any:
        if isinstance(value, bool) or (isinstance(value, float) and math.isfinite(value) and value == int(value)):
            value = int(value)
        elif not isinstance(value, int):
            raise ConversionError("%s: expected %s, got %s" % (path, base, _describe(value)))
        if not low <= value <= high:
            raise ConversionError("%s: %d out of range for %s" % (path, value, base))
        return value

    return conv


def _float_in(value: Any, path: str, ctx: Any) -> Any:
    if isinstance(value, float):
        return value
    if _is_int(value):
        return float(value)
    if value is None:
        return math.nan
    raise ConversionError("%s: expected a number, got %s" % (path, _describe(value)))


def _bool_in(value: Any, path: str, ctx: Any) -> Any:
    if isinstance(value, bool):
        return value
    if _is_int(value) and value in (0, 1):
        return bool(value)
    raise ConversionError("%s: expected a bool, got %s" % (path, _describe(value)))


def _string_in(value: Any, path: str, ctx: Any) -> Any:
    if isinstance(value, str):
        return value
    raise ConversionError("%s: expected a string, got %s" % (path, _describe(value)))


def _time_in(kind: str) -> Any:
    cls, low, high = (genpy.Time, 0, 2**32 - 1) if kind == "time" else (genpy.Duration, -(2**31), 2**31 - 1)

    def conv(value: Any, path: str, ctx: Any) -> Any:
        if value == "now" and kind == "time":
            return ctx.now()
        if isinstance(value, dict):
            unknown = set(value) - {"secs", "nsecs", "sec", "nanosec"}
            if unknown:
                raise ConversionError("%s: unknown field(s) %s in %s" % (path, sorted(unknown), kind))
            secs = value.get("secs", value.get("sec", 0))
            nsecs = value.get("nsecs", value.get("nanosec", 0))
            if not (_is_int(secs) and _is_int(nsecs)):
                raise ConversionError("%s: secs/nsecs must be integers" % path)
            if not (low <= secs <= high) or not (0 <= nsecs < 10**9 or kind == "duration"):
                raise ConversionError("%s: %s out of range" % (path, kind))
            return cls(secs, nsecs)
        if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
            if not (low <= value <= high):
                raise ConversionError("%s: %s out of range" % (path, kind))
            return cls.from_sec(value) if isinstance(value, float) else cls(value, 0)
        raise ConversionError("%s: expected {secs, nsecs}, got %s" % (path, _describe(value)))

    return conv


def _binary_in(fixed: Optional[int]) -> Any:
    def conv(value: Any, path: str, ctx: Any) -> Any:
        if isinstance(value, str):
            try:
                data = base64.b64decode(value.encode("ascii"), validate=True)
            except (binascii.Error, UnicodeEncodeError, ValueError):
                raise ConversionError("%s: invalid base64 string" % path) from None
        elif isinstance(value, list):
            try:
                data = bytes(value)
            except (TypeError, ValueError):
                raise ConversionError("%s: expected a list of ints 0..255" % path) from None
        else:
            raise ConversionError("%s: expected base64 string or list, got %s" % (path, _describe(value)))
        if fixed is not None and len(data) != fixed:
            raise ConversionError("%s: expected %d bytes, got %d" % (path, fixed, len(data)))
        return data

    return conv


def _array_in(elem: Any, fixed: Optional[int]) -> Any:
    def conv(value: Any, path: str, ctx: Any) -> Any:
        if not isinstance(value, list):
            raise ConversionError("%s: expected a list, got %s" % (path, _describe(value)))
        if fixed is not None and len(value) != fixed:
            raise ConversionError("%s: expected %d elements, got %d" % (path, fixed, len(value)))
        return [elem(v, "%s[%d]" % (path, i), ctx) for i, v in enumerate(value)]

    return conv


@functools.lru_cache(maxsize=None)
def _compile_in(cls: Any) -> Any:
    fields = {}
    header_slot = None
    for name, slot_type in zip(cls.__slots__, cls._slot_types):
        base, is_array, fixed = parse_type(slot_type)
        if base in _BINARY and is_array:
            elem, is_array = _binary_in(fixed), False  # converted whole, not per element
        elif base in _INT_RANGES:
            elem = _int_in(base)
        elif base in _FLOATS:
            elem = _float_in
        elif base == "bool":
            elem = _bool_in
        elif base == "string":
            elem = _string_in
        elif base in ("time", "duration"):
            elem = _time_in(base)
        else:
            nested = get_message_class(base)
            elem = functools.partial(_fill, nested)
            if nested._type == "std_msgs/Header" and not is_array:
                header_slot = name
        fields[name] = _array_in(elem, fixed) if is_array else elem
    return fields, header_slot


def _fill(cls: Any, data: Any, path: str, ctx: Any) -> Any:
    if not isinstance(data, dict):
        raise ConversionError("%s: expected an object for %s, got %s" % (path or "msg", cls._type, _describe(data)))
    fields, header_slot = _compile_in(cls)
    unknown = [k for k in data if k not in fields]
    if unknown:
        raise ConversionError(
            "%s: unknown field(s) %s for %s" % (path or "msg", ", ".join(sorted(map(str, unknown))), cls._type)
        )
    msg = cls()
    for key, value in data.items():
        setattr(msg, key, fields[key](value, (path + "." + key) if path else key, ctx))
    if len(data) < len(fields):
        ctx.missing.extend((path + "." + k) if path else k for k in fields if k not in data)
    if cls._type == "std_msgs/Header" and "stamp" not in data:
        msg.stamp = ctx.now()
    elif header_slot is not None and header_slot not in data:
        getattr(msg, header_slot).stamp = ctx.now()
    return msg


def dict_to_msg(cls: Any, data: Any, now: Callable[..., Any] = None) -> Any:
    """Build (message, paths of the fields filled with defaults) of class cls from a JSON object.

    Strict rosbridge mapping (``None`` is an empty object); ``now()`` gives the
    ``genpy.Time`` for missing header stamps (default: wall clock).

    Raises:
        ConversionError: On wrong types, unknown fields, out-of-range values.
    """
    ctx = types.SimpleNamespace(now=now or (lambda: genpy.Time.from_sec(time.time())), missing=[])
    return _fill(cls, {} if data is None else data, "", ctx), ctx.missing


def _describe(value: Any) -> str:
    text = repr(value)
    if len(text) > 40:
        text = text[:37] + "..."
    return "%s %s" % (type(value).__name__, text)


_EXAMPLES = dict(dict.fromkeys(_INT_RANGES, "0"), float32="0.0", float64="0.0", bool="False", string="")


def message_typedefs(cls: Any) -> Any:
    """Describe cls and every nested type as rosapi ``TypeDef`` dicts (message_details).

    Args:
        cls: genpy message class.

    Returns:
        list: One dict per type, cls first.
    """
    out, seen = [], set()

    def visit(c: Any) -> None:
        if c._type in seen:
            return
        seen.add(c._type)
        fields = [parse_type(slot_type) for slot_type in c._slot_types]
        # genpy makes each constant a class attribute, in definition order (rosapi reads them too)
        consts = [(k, v) for k, v in vars(c).items() if k[0] != "_" and isinstance(v, (int, float, str))]
        out.append(
            {
                "fieldnames": list(c.__slots__),
                "fieldtypes": [base for base, _, _ in fields],
                "fieldarraylen": [(fixed or 0) if is_array else -1 for _, is_array, fixed in fields],
                "examples": ["[]" if is_array else _EXAMPLES.get(base, "{}") for base, is_array, _ in fields],
                "constnames": [k for k, _ in consts],
                "constvalues": [str(v) for _, v in consts],
                "type": c._type,
            }
        )
        for base, _, _ in fields:
            if "/" in base:
                visit(get_message_class(base))

    visit(cls)
    return out
