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


def _split_array(slot_type: str) -> Any:  # (base type, is_array, fixed length or None)
    if slot_type.endswith("]"):
        base, _, rest = slot_type.partition("[")
        length = rest[:-1]
        return base, True, (int(length) if length else None)
    return slot_type, False, None


def _nested_class(base: str) -> Any:
    if base == "Header":
        base = "std_msgs/Header"
    return get_message_class(base)


# --------------------------------------------------------------------------- outgoing


def _finite(value: Any) -> Any:
    # inf - inf and nan - nan are nan; finite - finite is 0.0
    return value if value - value == 0 else None


def _time_out(value: Any) -> Any:
    return {"secs": value.secs, "nsecs": value.nsecs}


def _raw_bytes(value: Any) -> Any:
    if isinstance(value, str):  # old genpy hands out str for uint8[]
        value = value.encode("latin-1")
    return bytes(value)


def _b64(value: Any) -> Any:
    return base64.b64encode(_raw_bytes(value)).decode("ascii")


_out_cache = {}


def _compile_out(cls: Any, binary: bool) -> Any:
    key = (cls, binary)
    plan = _out_cache.get(key)
    if plan is not None:
        return plan
    plan = []
    for name, slot_type in zip(cls.__slots__, cls._slot_types):
        base, is_array, _ = _split_array(slot_type)
        conv = None
        if base in _BINARY and is_array:
            conv = _raw_bytes if binary else _b64
        elif base in _FLOATS:
            if is_array:
                conv = _typed(base) if binary else _float_list
            elif not binary:
                conv = _finite
        elif base in ("time", "duration"):
            conv = (lambda v: [_time_out(x) for x in v]) if is_array else _time_out
        elif base in _INT_RANGES or base in ("bool", "string"):
            if is_array:
                conv = _typed(base) if (binary and base in _INT_RANGES) else list
        else:
            conv = _nested_out(_nested_class(base), binary, is_array)
        plan.append((name, conv))
    plan = tuple(plan)
    _out_cache[key] = plan
    return plan


def _typed(kind: str) -> Any:
    return lambda v: TypedArray(kind, v)


def _float_list(values: Any) -> Any:
    return [v if v - v == 0 else None for v in values]  # (as _finite)


def _nested_out(nested_cls: Any, binary: bool, is_array: bool) -> Any:
    def one(value: Any) -> Any:
        return _convert_out(value, _compile_out(nested_cls, binary))

    if is_array:
        return lambda v: [one(x) for x in v]
    return one


def _convert_out(msg: Any, plan: Any) -> Any:
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
    return _convert_out(msg, _compile_out(type(msg), binary))


# --------------------------------------------------------------------------- incoming


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
    cls = genpy.Time if kind == "time" else genpy.Duration
    low = 0 if kind == "time" else -(2**31)
    high = 2**32 - 1 if kind == "time" else 2**31 - 1

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


_in_cache = {}


def _compile_in(cls: Any) -> Any:
    plan = _in_cache.get(cls)
    if plan is not None:
        return plan
    fields = {}
    header_slot = None
    for name, slot_type in zip(cls.__slots__, cls._slot_types):
        base, is_array, fixed = _split_array(slot_type)
        if base in _BINARY and is_array:
            fields[name] = _binary_in(fixed)
            continue
        if base in _INT_RANGES:
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
            nested = _nested_class(base)
            elem = functools.partial(_fill, nested)
            if nested._type == "std_msgs/Header" and not is_array:
                header_slot = name
        fields[name] = _array_in(elem, fixed) if is_array else elem
    plan = (fields, header_slot)
    _in_cache[cls] = plan
    return plan


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


_EXAMPLES = {"bool": "False", "string": "", "time": "{}", "duration": "{}"}


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
        names, types, lens, examples, nested = [], [], [], [], []
        for name, slot_type in zip(c.__slots__, c._slot_types):
            base, is_array, fixed = _split_array(slot_type)
            base = "std_msgs/Header" if base == "Header" else base
            primitive = base in _INT_RANGES or base in _FLOATS or base in _EXAMPLES
            names.append(name)
            types.append(base)
            lens.append((fixed or 0) if is_array else -1)
            if is_array:
                examples.append("[]")
            else:
                examples.append("0" if base in _INT_RANGES else "0.0" if base in _FLOATS else _EXAMPLES.get(base, "{}"))
            if not primitive:
                nested.append(_nested_class(base))
        constnames, constvalues = [], []
        for line in (getattr(c, "_full_text", "") or "").split("\n"):
            if line.startswith("==="):
                break
            line = line.split("#", 1)[0].strip()
            if "=" in line and " " in line.split("=", 1)[0].strip():
                left, value = line.split("=", 1)
                constnames.append(left.split()[-1])
                constvalues.append(value.strip())
        fields = (names, types, lens, examples, constnames, constvalues)
        keys = ("fieldnames", "fieldtypes", "fieldarraylen", "examples", "constnames", "constvalues")
        out.append(dict(zip(keys, fields), type=c._type))
        for n in nested:
            visit(n)

    visit(cls)
    return out
