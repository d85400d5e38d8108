"""rbd_bringup.cloud_thin on clouds packed here in the ouster-ros layout (INTERFACES.md §1).

point_type original: x, y, z FLOAT32 @0/4/8, intensity FLOAT32 @16, t UINT32 @20, reflectivity
UINT16 @24, ring UINT16 @26, ambient UINT16 @28, range UINT32 @32, point_step 48, little-endian.
"""

import math
import struct

import numpy as np
import pytest

from rbd_bringup.cloud_thin import CloudLayoutError, Throttle, column_step, thin_cloud

FIELDS = {"x": (0, 7), "y": (4, 7), "z": (8, 7), "intensity": (16, 7), "t": (20, 6), "reflectivity": (24, 4),
          "ring": (26, 4), "ambient": (28, 4), "range": (32, 6)}


def ouster_cloud(height, width, invalid=()):
    """Point (r, c) at x = c, y = r, z = 0.5, range = 1000 r + c + 1 mm; `invalid` pixels get NaN and range 0."""
    buf = bytearray(48 * width * height)
    for r in range(height):
        for c in range(width):
            off = 48 * (r * width + c)
            if (r, c) in invalid:
                struct.pack_into("<fff", buf, off, math.nan, math.nan, math.nan)
                struct.pack_into("<I", buf, off + 32, 0)
            else:
                struct.pack_into("<fff", buf, off, float(c), float(r), 0.5)
                struct.pack_into("<I", buf, off + 32, 1000 * r + c + 1)
            struct.pack_into("<f", buf, off + 12, 1.0)
            struct.pack_into("<fIHHH", buf, off + 16, 77.0, 5, 9, r, 3)
    return bytes(buf)


def unpack(data):
    return np.frombuffer(data, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("c", "<u4")])


def test_keeps_every_nth_column_and_drops_points_without_return():
    h, w = 4, 16
    data = ouster_cloud(h, w, invalid={(1, 4), (2, 0)})
    out, n, kind = thin_cloud(data, h, w, 48, 48 * w, FIELDS, "range", column_step(w, 4))
    assert column_step(w, 4) == 4 and kind == 6  # range stays UINT32 (mm)
    pts = unpack(out)
    assert n == len(pts) == h * 4 - 2
    kept = {(int(p["y"]), int(p["x"])) for p in pts}
    assert kept == {(r, c) for r in range(h) for c in (0, 4, 8, 12)} - {(1, 4), (2, 0)}
    for p in pts:
        assert p["z"] == 0.5 and p["c"] == 1000 * int(p["y"]) + int(p["x"]) + 1


def test_rows_and_float_channel():
    h, w = 6, 8
    out, n, kind = thin_cloud(ouster_cloud(h, w), h, w, 48, 48 * w, FIELDS, "intensity", 1, row_every=3)
    pts = np.frombuffer(out, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("c", "<f4")])
    assert kind == 7 and n == 2 * w
    assert sorted({int(v) for v in pts["y"]}) == [0, 3]
    assert np.all(pts["c"] == 77.0)


def test_padded_rows_and_older_ouster_zero_points():
    h, w = 2, 4
    data = bytearray(ouster_cloud(h, w))
    struct.pack_into("<fff", data, 48 * 5, 0.0, 0.0, 0.0)  # ouster-ros < 0.13: no return = (0, 0, 0)
    padded = b"".join(bytes(data[48 * w * r:48 * w * (r + 1)]) + b"\0" * 16 for r in range(h))
    out, n, _ = thin_cloud(padded, h, w, 48, 48 * w + 16, FIELDS, "range", 1)
    assert n == h * w - 1
    assert (1, 1) not in {(int(p["y"]), int(p["x"])) for p in unpack(out)}


@pytest.mark.parametrize("fields, size, message", [
    ({k: v for k, v in FIELDS.items() if k != "range"}, None, "channel"),
    (dict(FIELDS, x=(0, 8)), None, "field x"),
    (FIELDS, 48 * 8 * 2 - 1, "data size"),
    (dict(FIELDS, range=(46, 6)), None, "does not fit"),
])
def test_layout_errors(fields, size, message):
    data = ouster_cloud(2, 8)
    if size is not None:
        data = data[:size]
    with pytest.raises(CloudLayoutError) as err:
        thin_cloud(data, 2, 8, 48, 48 * 8, fields, "range", 2)
    assert message in str(err.value)


def test_column_step():
    assert [column_step(w, 256) for w in (512, 1024, 2048)] == [2, 4, 8]
    assert column_step(100, 256) == 1


def test_throttle_halves_a_10hz_stream_with_jitter():
    th = Throttle(5.0)
    stamps = [0.1 * i + (0.004 if i % 3 else -0.003) for i in range(50)]
    sent = [s for s in stamps if th.ready(s)]
    assert len(sent) == 25
    with pytest.raises(ValueError):
        Throttle(0.0)
