"""OS1 model: ouster-ros layout of packed clouds, beam geometry, noise, min range, modes."""

import json
import math
import struct

import numpy as np
import pytest

from rbd_geometry.rotation import rpy_to_matrix
from rbd_sim import os1
from rbd_sim.shapes import Box, Cylinder
from rbd_sim.world import World

META = os1.load_metadata(os1.DEFAULT_METADATA)
LEVEL = (np.eye(3), np.array([0.0, 0.0, 0.35]))


def hall():
    w = World("hall", 0.0, 3.0)
    for cx, cy, hx, hy in ((8, 0, 0.1, 8), (-8, 0, 0.1, 8), (0, 8, 8, 0.1), (0, -8, 8, 0.1)):
        w.boxes.append(Box("w", cx, cy, hx, hy, 0.0, 3.0))
    w.boxes.append(Box("target", 2.25, 0.0, 0.25, 0.5, 0.0, 1.0))
    return w


@pytest.mark.parametrize("columns, hz", [(512, 10), (512, 20), (1024, 10), (1024, 20), (2048, 10)])
def test_packed_layout(columns, hz):
    m = os1.Os1Model(META, columns, hz, seed=1)
    scan = m.scan(*LEVEL, hall(), 0.0)
    data = m.pack(scan)
    assert len(data) == 48 * 32 * columns
    assert os1.POINT_STEP == 48
    assert [f[:2] for f in os1.POINT_FIELDS] == [
        ("x", 0),
        ("y", 4),
        ("z", 8),
        ("intensity", 16),
        ("t", 20),
        ("reflectivity", 24),
        ("ring", 26),
        ("ambient", 28),
        ("range", 32),
    ]
    assert [f[2] for f in os1.POINT_FIELDS] == [7, 7, 7, 7, 6, 4, 4, 4, 6]
    for row, col in ((0, 0), (17, columns // 2), (31, columns - 1)):
        off = (row * columns + col) * 48
        x, y, z, pad, inten, t, refl, ring, amb = struct.unpack_from("<fffffIHHH", data, off)
        (rng,) = struct.unpack_from("<I", data, off + 32)
        assert ring == row and pad == 1.0
        assert rng == scan.range_mm[row, col] and rng > 0
        assert t == pytest.approx(col * 1e9 / (hz * columns), abs=1)
        # xyz is what ouster-sdk's LUT gives for this range: |p - beam origin| = range - n
        assert math.isfinite(x) and math.isfinite(y) and math.isfinite(z)
        assert data[off + 36 : off + 48] == b"\0" * 12 and data[off + 30 : off + 32] == b"\0\0"


def test_unsupported_modes_rejected():
    for cols, hz in ((2048, 20), (4096, 5), (1000, 10)):
        with pytest.raises(ValueError, match="unsupported"):
            os1.Os1Model(META, cols, hz)


def test_geometry_matches_sdk_formula():
    """col 0 looks to -X of os_sensor, col W/2 to +X (the connector is at -X); 10 m -> |p| 10.008 m is for G units."""
    m = os1.Os1Model(META, 1024, 10, seed=0)
    d = m.directions
    assert np.allclose(np.linalg.norm(d, axis=-1), 1.0)
    az = np.degrees(np.arctan2(d[15, :, 1], d[15, :, 0]))
    assert abs(abs(az[0]) - 180.0 + 4.26) < 0.05  # beam azimuth offset -4.26 deg
    assert abs(az[512] - 4.26) < 0.05
    np.testing.assert_allclose(np.degrees(np.arcsin(d[:, 0, 2])), META["beam_altitude_angles"], atol=1e-9)
    # Beam origins on a 15.806 mm circle around the lidar axis, 36.18 mm above os_sensor.
    np.testing.assert_allclose(np.hypot(m.origins[:, 0], m.origins[:, 1]), 0.015806)
    np.testing.assert_allclose(m.origins[:, 2], 0.03618)


def test_box_in_front_and_noise_bounds():
    m = os1.Os1Model(META, 1024, 10, range_noise_std=0.01, range_noise_max=0.03, seed=2)
    clean = os1.Os1Model(META, 1024, 10, range_noise_std=0.0, seed=2)
    a = m.scan(*LEVEL, hall(), 0.0)
    b = clean.scan(*LEVEL, hall(), 0.0)
    diff = a.range_mm.astype(np.int64) - b.range_mm.astype(np.int64)
    assert np.abs(diff).max() <= 31
    assert 6 < diff.std() < 14
    row = 15  # +0.18 deg
    col = int(np.argmin(np.abs(np.arctan2(clean.directions[row, :, 1], clean.directions[row, :, 0]))))
    assert b.range_mm[row, col] == pytest.approx(2000, abs=2)
    assert a.range_mm[row, col] == pytest.approx(2000, abs=32)
    xyz = b.xyz()
    assert xyz[row, col, 0] == pytest.approx(2.0, abs=0.002)


def test_noise_is_seeded():
    w = hall()
    r1 = [os1.Os1Model(META, 512, 10, seed=7).scan(*LEVEL, w, 0.0).range_mm for _ in range(2)]
    r2 = os1.Os1Model(META, 512, 10, seed=8).scan(*LEVEL, w, 0.0).range_mm
    assert np.array_equal(r1[0], r1[1])
    assert not np.array_equal(r1[0], r2)
    m = os1.Os1Model(META, 512, 10, seed=7)
    s1, s2 = m.scan(*LEVEL, w, 0.0).range_mm, m.scan(*LEVEL, w, 0.0).range_mm
    assert not np.array_equal(s1, s2)  # fresh noise every scan


def test_min_range_and_no_return_give_zero_and_nan():
    w = World("t", 0.0, None)
    w.place("close", 0.25, 0.0, 0.05, 2.0)  # 0.2 m in front of the axis: under the 0.3 m minimum
    m = os1.Os1Model(META, 512, 10, seed=0)
    s = m.scan(*LEVEL, w, 0.0)
    data = np.frombuffer(m.pack(s), dtype=os1.POINT_DTYPE).reshape(32, 512)
    col = 256 + 6  # facing +x
    assert np.all(data["range"][10:20, col] == 0)
    assert np.all(np.isnan(data["x"][10:20, col]))
    assert np.all(data["range"][0, :] == 0)  # upward beams: no ceiling, nothing to hit
    assert not m.is_dense(s)
    legacy = os1.Os1Model(META, 512, 10, seed=0, nan_invalid=False)
    s = legacy.scan(*LEVEL, w, 0.0)
    data = np.frombuffer(legacy.pack(s), dtype=os1.POINT_DTYPE).reshape(32, 512)
    assert np.all(data["x"][0, :] == 0.0) and legacy.is_dense(s)


def test_destagger_follows_pixel_shift():
    meta = json.loads(json.dumps(META))
    shifts = [(i % 4) * 4 for i in range(32)]
    meta["data_format"]["pixel_shift_by_row"] = shifts
    meta["data_format"]["columns_per_frame"] = 512
    staggered = os1.Os1Model(META, 512, 10, range_noise_std=0.0, seed=0)
    shifted = os1.Os1Model(meta, 512, 10, range_noise_std=0.0, seed=0)
    w = hall()
    a = staggered.scan(*LEVEL, w, 0.0).range_mm
    b = shifted.scan(*LEVEL, w, 0.0).range_mm
    for u in range(32):
        assert np.array_equal(b[u], np.roll(a[u], shifts[u]))


def test_tilt_moves_floor():
    w = World("floor", 0.0, None)
    m = os1.Os1Model(META, 512, 10, range_noise_std=0.0, seed=0)
    level = m.scan(np.eye(3), np.array([0, 0, 0.35]), w, 0.0).range_mm[31]
    pitched = m.scan(rpy_to_matrix(0, 0.2, 0), np.array([0, 0, 0.35]), w, 0.0).range_mm[31]
    front, back = 256 + 6, 6
    assert pitched[front] < level[front] - 250
    assert pitched[back] > level[back] + 500


def test_metadata_json_reports_mode():
    m = os1.Os1Model(META, 2048, 10)
    meta = json.loads(m.metadata_json())
    assert meta["lidar_mode"] == "2048x10"
    assert meta["data_format"]["columns_per_frame"] == 2048
    assert len(meta["beam_altitude_angles"]) == 32


def test_bad_metadata_rejected():
    meta = dict(META)
    meta["beam_azimuth_angles"] = meta["beam_azimuth_angles"][:-1]
    with pytest.raises(ValueError, match="same non-zero length"):
        os1.Os1Model(meta)
    with pytest.raises(ValueError, match="lacks"):
        os1.check_metadata({})


def test_motion_distortion_forward_and_turning():
    w = hall()
    m = os1.Os1Model(META, 512, 10, range_noise_std=0.0, seed=0)
    pos = np.array([0.0, 0.0, 1.5])  # above the target box: front beams reach the hall wall at x = 7.9
    still = m.scan(np.eye(3), pos, w, 0.0).range_mm
    moving = m.scan(np.eye(3), pos, w, 0.0, velocity=np.array([1.0, 0.0, 0.0])).range_mm
    front, back = 256 + 6, 6  # +x column fired at ~0.05 s, -x column at ~0 s
    row = 15
    assert still[row, front] - moving[row, front] == pytest.approx(51, abs=3)  # 1 m/s x 0.051 s
    assert abs(int(still[row, back]) - int(moving[row, back])) <= 2
    # Turning at 1 rad/s: a thin pillar straight ahead shows up ~4 columns later.
    w2 = World("p", 0.0, None)
    w2.cylinders.append(Cylinder("pillar", 3.0, 0.0, 0.05, 0.0, 3.0))
    a = m.scan(np.eye(3), pos, w2, 0.0)
    b = m.scan(np.eye(3), pos, w2, 0.0, yaw_rate=1.0)
    ca = np.flatnonzero(a.hit[row] >= 2).mean()
    cb = np.flatnonzero(b.hit[row] >= 2).mean()
    assert 3.0 <= cb - ca <= 5.5


def test_mount_pose_of_a_calibration_file_entry():
    from rbd_sim.mounts import mount_pose

    entry = {"parent": "base_link", "xyz": [-0.08, 0, 0.07], "rpy": [0, 0.1, 3]}
    assert mount_pose(entry, "os_sensor") == [-0.08, 0.0, 0.07, 0.0, 0.1, 3.0]
    for bad, key in (({"xyz": [0, 0], "rpy": [0, 0, 0]}, "xyz"), ({"xyz": [0, 0, 0]}, "rpy"),
                     ({"xyz": [0, 0, 0], "rpy": [0, "a", 0]}, "rpy"),
                     ({"xyz": [0, float("inf"), 0], "rpy": [0, 0, 0]}, "xyz")):
        with pytest.raises(ValueError) as err:
            mount_pose(bad, "os_sensor")
        assert "os_sensor.%s" % key in str(err.value)
    with pytest.raises(ValueError):
        mount_pose([0, 0, 0.07, 0, 0, 0], "os_sensor")
