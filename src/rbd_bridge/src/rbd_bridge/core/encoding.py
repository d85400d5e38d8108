"""Wire encodings of rosbridge v2: JSON, CBOR (cbor2, with typed-array tags), PNG, fragments."""

import base64
import collections
import io
import json
import math
import struct
import zlib
from typing import Any, List

import cbor2

from rbd_bridge.core.types import TypedArray

__all__ = ["DecodeError", "Reassembler", "json_dumps", "cbor_dumps", "cbor_loads", "png_encode", "fragment"]


class DecodeError(ValueError):
    """Bytes that are not a valid frame."""


_json_encoder = json.JSONEncoder(ensure_ascii=False, separators=(",", ":"), allow_nan=False)


def _sanitize(value: Any) -> Any:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _sanitize(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_sanitize(v) for v in value]
    return value


def json_dumps(obj: Any) -> str:
    """Serialize obj compactly; non-finite floats become null (never the NaN literal)."""
    try:
        return _json_encoder.encode(obj)
    except ValueError:
        return _json_encoder.encode(_sanitize(obj))


# RFC 8746 typed arrays, little-endian: ROS element type -> (tag, struct format)
_TYPED_TAGS = {"uint8": (64, "B"), "char": (64, "B"), "int8": (72, "b"), "byte": (72, "b"), "uint16": (69, "H")}
_TYPED_TAGS.update(uint32=(70, "I"), uint64=(71, "Q"), int16=(77, "h"), int32=(78, "i"), int64=(79, "q"))
_TYPED_TAGS.update(float32=(85, "f"), float64=(86, "d"))
_TAG_FORMATS = {tag: fmt for tag, fmt in _TYPED_TAGS.values()}


def _typed_array(encoder: Any, value: Any) -> None:
    if not isinstance(value, TypedArray):
        raise ValueError("cannot CBOR-encode %s" % type(value).__name__)
    tag, fmt = _TYPED_TAGS[value.kind]
    values = value.values
    if not isinstance(values, (bytes, bytearray)):
        values = struct.pack("<%d%s" % (len(values), fmt), *values)
    encoder.encode(cbor2.CBORTag(tag, bytes(values)))


def cbor_dumps(obj: Any) -> bytes:
    """Encode obj as CBOR (:class:`TypedArray` values as RFC 8746 typed-array tags)."""
    return cbor2.dumps(obj, default=_typed_array)


def _untag(value: Any) -> Any:
    """Typed-array tags to lists (uint8 to bytes), other tags to their content."""
    if isinstance(value, dict):
        return {k: _untag(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_untag(v) for v in value]
    if isinstance(value, cbor2.CBORTag):
        fmt = _TAG_FORMATS.get(value.tag)
        inner = value.value
        if fmt is None or not isinstance(inner, bytes):
            return _untag(inner)
        if fmt == "B":
            return inner
        size = struct.calcsize(fmt)
        if len(inner) % size:
            raise DecodeError("typed array length not a multiple of its element size")
        return list(struct.unpack("<%d%s" % (len(inner) // size, fmt), inner))
    return value


def cbor_loads(data: Any) -> Any:
    """Decode one CBOR item that fills the whole buffer (typed arrays to lists, uint8 ones to bytes).

    Raises:
        DecodeError: On malformed, too deeply nested or trailing data.
    """
    stream = io.BytesIO(bytes(data))
    try:
        value = _untag(cbor2.CBORDecoder(stream).decode())
    except (cbor2.CBORDecodeError, ValueError, TypeError, OverflowError, RecursionError, MemoryError) as exc:
        raise DecodeError("invalid CBOR: %s" % str(exc)[:100]) from None
    if stream.tell() != len(stream.getbuffer()):
        raise DecodeError("trailing bytes after CBOR item")
    return value


def png_encode(text: str) -> str:
    """The ``data`` of a ``png`` op: the UTF-8 bytes of text as an 8-bit RGB PNG, base64.

    Padded with newlines, as rosbridge's: clients parse the pixels as JSON text, where trailing
    newlines are whitespace (NUL bytes make ``JSON.parse`` throw).
    """
    raw = text.encode("utf-8")
    pixels = max(1, (len(raw) + 2) // 3)
    width = max(1, int(math.ceil(math.sqrt(pixels))))
    height = (pixels + width - 1) // width
    raw = raw + b"\n" * (width * height * 3 - len(raw))
    stride = width * 3
    rows = b"".join(b"\x00" + raw[y * stride : (y + 1) * stride] for y in range(height))
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    png = [b"\x89PNG\r\n\x1a\n"]
    for chunk in (b"IHDR" + header, b"IDAT" + zlib.compress(rows, 6), b"IEND"):  # each: length, type+data, CRC
        png += [struct.pack(">I", len(chunk) - 4), chunk, struct.pack(">I", zlib.crc32(chunk))]
    return base64.b64encode(b"".join(png)).decode("ascii")


def fragment(text: str, size: int, frag_id: Any, op: str = "fragment") -> List[str]:
    """Split text into ``fragment`` (or ``png``) op frames (JSON texts) of at most size characters of data."""
    size = max(1, int(size))
    data = [text[i : i + size] for i in range(0, len(text), size)]
    return [json_dumps({"op": op, "id": frag_id, "data": d, "num": i, "total": len(data)}) for i, d in enumerate(data)]


class Reassembler:
    """Joins incoming ``fragment`` ops (any order; at most max_sets open sets, ttl s each, total <= max_fragments)."""

    def __init__(self, max_sets: int = 32, ttl: float = 30.0, max_fragments: int = 100000) -> None:
        self.max_sets = max_sets
        self.ttl = ttl
        self.max_fragments = max_fragments
        self._sets = collections.OrderedDict()

    def add(self, frame: Any, now: float, max_size: Any = None) -> Any:
        """Take one fragment frame; return the whole text once the set is complete, else None.

        Raises:
            DecodeError: A malformed fragment, or a set larger than max_size.
        """
        frag_id, data, num, total = (frame.get(k) for k in ("id", "data", "num", "total"))
        if not isinstance(frag_id, (str, int)) or isinstance(frag_id, bool) or not isinstance(data, str):
            raise DecodeError("needs a string/int 'id' and a string 'data'")
        if not all(isinstance(v, int) and not isinstance(v, bool) for v in (num, total)):
            raise DecodeError("'num' and 'total' must be integers")
        if not (0 < total <= self.max_fragments and 0 <= num < total):
            raise DecodeError("num/total out of range")
        for key in [k for k, v in self._sets.items() if now - v["t"] > self.ttl]:
            del self._sets[key]
        entry = self._sets.get(frag_id)
        if entry is None or entry["total"] != total:
            if len(self._sets) >= self.max_sets:
                self._sets.popitem(last=False)
            entry = self._sets[frag_id] = {"total": total, "parts": {}, "size": 0, "t": now}
        entry["size"] += len(data) - len(entry["parts"].get(num, ""))  # a repeated part replaces the earlier one
        entry["parts"][num] = data
        if max_size and entry["size"] > max_size:
            del self._sets[frag_id]
            raise DecodeError("reassembled message exceeds max_message_size")
        if len(entry["parts"]) < total:
            return None
        del self._sets[frag_id]
        return "".join(entry["parts"][i] for i in range(total))
