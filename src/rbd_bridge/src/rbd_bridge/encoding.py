"""Wire encodings of rosbridge v2: JSON, CBOR (with typed-array tags), PNG, fragments.

ROS-free. The CBOR encoder/decoder covers what rosbridge frames contain (maps, arrays,
strings, byte strings, ints, floats, bools, null, typed arrays); it is not a general library.
"""

import base64
import json
import math
import struct
import zlib
from typing import Any

from rbd_bridge.msgconv import TypedArray

__all__ = [
    "DecodeError",
    "json_dumps",
    "cbor_dumps",
    "cbor_loads",
    "png_encode",
    "png_decode",
    "fragment",
]


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


def json_dumps(obj: Any) -> Any:
    """Serialize obj compactly; non-finite floats become null (never the NaN literal).

    Args:
        obj: JSON-ready object.

    Returns:
        str: The JSON text.
    """
    try:
        return _json_encoder.encode(obj)
    except ValueError:
        return _json_encoder.encode(_sanitize(obj))


# --------------------------------------------------------------------------- CBOR

# draft-ietf-cbor-array-tags: little-endian typed array tags
_TYPED_TAGS = {
    "uint8": (64, "B"),
    "char": (64, "B"),
    "int8": (72, "b"),
    "byte": (72, "b"),
    "uint16": (69, "<H"),
    "uint32": (70, "<I"),
    "uint64": (71, "<Q"),
    "int16": (77, "<h"),
    "int32": (78, "<i"),
    "int64": (79, "<q"),
    "float32": (85, "<f"),
    "float64": (86, "<d"),
}
_TAG_FORMATS = {tag: fmt for tag, fmt in _TYPED_TAGS.values()}


def _head(major: int, value: Any) -> Any:
    if value < 24:
        return struct.pack("B", (major << 5) | value)
    if value < 0x100:
        return struct.pack("BB", (major << 5) | 24, value)
    if value < 0x10000:
        return struct.pack(">BH", (major << 5) | 25, value)
    if value < 0x100000000:
        return struct.pack(">BI", (major << 5) | 26, value)
    return struct.pack(">BQ", (major << 5) | 27, value)


def _cbor_encode(value: Any, out: Any) -> None:
    if value is None:
        out.append(b"\xf6")
    elif value is True:
        out.append(b"\xf5")
    elif value is False:
        out.append(b"\xf4")
    elif isinstance(value, int):
        if value >= 0:
            if value >= 2**64:
                raise ValueError("integer too large for CBOR")
            out.append(_head(0, value))
        else:
            if value < -(2**64):
                raise ValueError("integer too small for CBOR")
            out.append(_head(1, -1 - value))
    elif isinstance(value, float):
        out.append(struct.pack(">Bd", 0xFB, value))
    elif isinstance(value, str):
        raw = value.encode("utf-8")
        out.append(_head(3, len(raw)))
        out.append(raw)
    elif isinstance(value, (bytes, bytearray)):
        out.append(_head(2, len(value)))
        out.append(bytes(value))
    elif isinstance(value, dict):
        out.append(_head(5, len(value)))
        for key, item in value.items():
            _cbor_encode(key, out)
            _cbor_encode(item, out)
    elif isinstance(value, (list, tuple)):
        out.append(_head(4, len(value)))
        for item in value:
            _cbor_encode(item, out)
    elif isinstance(value, TypedArray):
        tag, fmt = _TYPED_TAGS[value.kind]
        values = value.values
        if isinstance(values, (bytes, bytearray)):
            raw = bytes(values)
        else:
            raw = struct.pack("<%d%s" % (len(values), fmt[-1]), *values)
        out.append(_head(6, tag))
        out.append(_head(2, len(raw)))
        out.append(raw)
    else:
        raise ValueError("cannot CBOR-encode %s" % type(value).__name__)


def cbor_dumps(obj: Any) -> Any:
    """Encode obj as CBOR bytes (typed arrays get draft array tags).

    Args:
        obj: dict/list/str/bytes/int/float/bool/None/TypedArray tree.

    Returns:
        bytes: The CBOR encoding.
    """
    out = []
    _cbor_encode(obj, out)
    return b"".join(out)


class _Reader:
    __slots__ = ("data", "pos", "depth")

    def __init__(self, data: Any) -> None:
        self.data = data
        self.pos = 0
        self.depth = 0

    def take(self, n: int) -> Any:
        if n < 0 or self.pos + n > len(self.data):
            raise DecodeError("truncated CBOR")
        chunk = self.data[self.pos : self.pos + n]
        self.pos += n
        return chunk


def _read_arg(reader: Any, info: int) -> Any:
    if info < 24:
        return info
    if info == 24:
        return reader.take(1)[0]
    if info == 25:
        return struct.unpack(">H", reader.take(2))[0]
    if info == 26:
        return struct.unpack(">I", reader.take(4))[0]
    if info == 27:
        return struct.unpack(">Q", reader.take(8))[0]
    raise DecodeError("unsupported CBOR length encoding %d" % info)


def _cbor_decode(reader: Any) -> Any:
    reader.depth += 1
    if reader.depth > 64:
        raise DecodeError("CBOR nested too deeply")
    first = reader.take(1)[0]
    major, info = first >> 5, first & 0x1F
    if major == 7:
        reader.depth -= 1
        if info == 20:
            return False
        if info == 21:
            return True
        if info in (22, 23):
            return None
        if info == 25:
            return _half(struct.unpack(">H", reader.take(2))[0])
        if info == 26:
            return struct.unpack(">f", reader.take(4))[0]
        if info == 27:
            return struct.unpack(">d", reader.take(8))[0]
        raise DecodeError("unsupported CBOR simple value %d" % info)
    arg = _read_arg(reader, info)
    if major == 0:
        value = arg
    elif major == 1:
        value = -1 - arg
    elif major == 2:
        value = bytes(reader.take(arg))
    elif major == 3:
        try:
            value = bytes(reader.take(arg)).decode("utf-8")
        except UnicodeDecodeError:
            raise DecodeError("invalid UTF-8 in CBOR text") from None
    elif major == 4:
        if arg > len(reader.data):
            raise DecodeError("CBOR array longer than the frame")
        value = [_cbor_decode(reader) for _ in range(arg)]
    elif major == 5:
        if arg > len(reader.data):
            raise DecodeError("CBOR map longer than the frame")
        value = {}
        for _ in range(arg):
            key = _cbor_decode(reader)
            if not isinstance(key, (str, int)):
                raise DecodeError("CBOR map key must be text or int")
            value[key] = _cbor_decode(reader)
    else:  # tag
        inner = _cbor_decode(reader)
        fmt = _TAG_FORMATS.get(arg)
        if fmt is not None and isinstance(inner, bytes):
            size = struct.calcsize(fmt)
            if len(inner) % size:
                raise DecodeError("typed array length not a multiple of its element size")
            value = list(struct.unpack("<%d%s" % (len(inner) // size, fmt[-1]), inner))
            if arg == 64:
                value = inner
        else:
            value = inner
    reader.depth -= 1
    return value


def _half(bits: int) -> Any:
    sign = -1.0 if bits & 0x8000 else 1.0
    exp = (bits >> 10) & 0x1F
    frac = bits & 0x3FF
    if exp == 0:
        return sign * frac * 2.0**-24
    if exp == 31:
        return sign * math.inf if frac == 0 else math.nan
    return sign * (1 + frac / 1024.0) * 2.0 ** (exp - 15)


def cbor_loads(data: Any) -> Any:
    """Decode one CBOR item that fills the whole buffer.

    Args:
        data: bytes.

    Returns:
        The decoded object (typed arrays become lists, uint8 typed arrays bytes).

    Raises:
        DecodeError: On malformed or trailing data.
    """
    reader = _Reader(memoryview(bytes(data)))
    value = _cbor_decode(reader)
    if reader.pos != len(reader.data):
        raise DecodeError("trailing bytes after CBOR item")
    return value


# --------------------------------------------------------------------------- PNG


def _png_chunk(kind: str, payload: Any) -> Any:
    body = kind + payload
    return struct.pack(">I", len(payload)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


def png_encode(text: str) -> Any:
    """Pack the UTF-8 bytes of text into an 8-bit RGB PNG (padded with newlines) and base64 it.

    The padding is ``\\n`` as rosbridge's: a client decodes the pixels to text and parses
    it as JSON, where trailing newlines are whitespace (NUL bytes make ``JSON.parse`` throw).

    Args:
        text: The JSON string of a frame.

    Returns:
        str: base64 of the PNG file (the ``data`` of a ``png`` op).
    """
    raw = text.encode("utf-8")
    pixels = max(1, (len(raw) + 2) // 3)
    width = max(1, int(math.ceil(math.sqrt(pixels))))
    height = (pixels + width - 1) // width
    raw = raw + b"\n" * (width * height * 3 - len(raw))
    stride = width * 3
    rows = b"".join(b"\x00" + raw[y * stride : (y + 1) * stride] for y in range(height))
    png = b"".join(
        [
            b"\x89PNG\r\n\x1a\n",
            _png_chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)),
            _png_chunk(b"IDAT", zlib.compress(rows, 6)),
            _png_chunk(b"IEND", b""),
        ]
    )
    return base64.b64encode(png).decode("ascii")


def png_decode(data: Any) -> Any:
    """Inverse of :func:`png_encode` (for tests and tools; filter type 0 only).

    Args:
        data: base64 text of the PNG.

    Returns:
        str: The embedded text with the padding removed.
    """
    png = base64.b64decode(data)
    if png[:8] != b"\x89PNG\r\n\x1a\n":
        raise DecodeError("not a PNG")
    pos, idat, width = 8, [], 0
    while pos < len(png):
        (length,) = struct.unpack(">I", png[pos : pos + 4])
        kind = png[pos + 4 : pos + 8]
        payload = png[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            width = struct.unpack(">I", payload[:4])[0]
        elif kind == b"IDAT":
            idat.append(payload)
        pos += 12 + length
    rows = zlib.decompress(b"".join(idat))
    stride = width * 3 + 1
    raw = b"".join(rows[i + 1 : i + stride] for i in range(0, len(rows), stride))
    return raw.rstrip(b"\n\x00").decode("utf-8")


# --------------------------------------------------------------------------- fragments


def fragment(text: str, size: int, frag_id: Any) -> Any:
    """Split a frame's JSON text into ``fragment`` op frames of at most size characters of data.

    Args:
        text: The JSON text of the whole frame.
        size: Maximum characters of data per fragment (>= 1).
        frag_id: The id shared by all fragments.

    Returns:
        list: JSON texts of the fragment frames (a single-element list holding text itself
        when it already fits).
    """
    if size is None or len(text) <= size:
        return [text]
    size = max(1, int(size))
    total = (len(text) + size - 1) // size
    return [
        json_dumps({"op": "fragment", "id": frag_id, "data": text[i * size : (i + 1) * size], "num": i, "total": total})
        for i in range(total)
    ]
