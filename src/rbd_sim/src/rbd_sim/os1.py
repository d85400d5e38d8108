"""Simulated Ouster OS1-32: beam geometry from sensor metadata, scans, ouster-ros cloud layout.

ROS-free. Geometry follows ouster-sdk's ``xyzlut``: for staggered column c of W and row u,
encoder angle te = 2*pi*(1 - c/W), beam azimuth ta = -azimuth[u], altitude phi = altitude[u];
direction d = (cos(te+ta) cos(phi), sin(te+ta) cos(phi), sin(phi)) in the lidar frame; the
beam leaves the lidar axis at n = lidar_origin_to_beam_origin_mm along (cos te, sin te, 0);
``range`` is measured from the lidar axis, so a return at distance s from the beam origin has
range s + n and xyz = range * d + (n cos te - n d_x, n sin te - n d_y, -n d_z). Directions and
offsets are then taken into ``os_sensor`` with lidar_to_sensor_transform (mm -> m).

Output emulates ouster-ros v0.13/v0.14 (``master``) with ``point_type:=original``,
``organized:=true``, ``destagger:=true``: 48-byte points, height 32 (row 0 = top beam), width
= columns; a zero range (no return, or closer than the 0.3 m hardware minimum of Rev 6 and
earlier units, where the sensor itself reports 0) gives NaN x, y, z and ``is_dense`` false,
while the ``range`` field stays the raw value (0). ``nan_invalid=False`` emulates ouster-ros
before v0.13 (x, y, z = 0, is_dense true).
"""

import json
import math
import os

import numpy as np

from rbd_sim.raycast import FIRST_PRIMITIVE_ID, Raycaster

VALID_COLUMNS = (512, 1024, 2048)
VALID_HZ = (10, 20)
#: Modes the OS1 supports (columns x Hz); 2048 only at 10 Hz.
VALID_MODES = ((512, 10), (512, 20), (1024, 10), (1024, 20), (2048, 10))

# PointField datatypes (sensor_msgs/PointField constants).
UINT16, UINT32, FLOAT32 = 4, 6, 7
#: (name, offset, datatype) of ouster-ros ``original`` points, in message order.
POINT_FIELDS = (
    ("x", 0, FLOAT32),
    ("y", 4, FLOAT32),
    ("z", 8, FLOAT32),
    ("intensity", 16, FLOAT32),
    ("t", 20, UINT32),
    ("reflectivity", 24, UINT16),
    ("ring", 26, UINT16),
    ("ambient", 28, UINT16),
    ("range", 32, UINT32),
)
POINT_STEP = 48
POINT_DTYPE = np.dtype(
    {
        "names": ["x", "y", "z", "pad", "intensity", "t", "reflectivity", "ring", "ambient", "range"],
        "formats": ["<f4", "<f4", "<f4", "<f4", "<f4", "<u4", "<u2", "<u2", "<u2", "<u4"],
        "offsets": [0, 4, 8, 12, 16, 20, 24, 26, 28, 32],
        "itemsize": POINT_STEP,
    }
)

DEFAULT_METADATA = os.path.join(os.path.dirname(__file__), "..", "..", "config", "os1-32-u0.json")


def load_metadata(path: str) -> dict:
    """Read an Ouster sensor metadata JSON file (legacy/FW 2.x flat format).

    Raises:
        ValueError: missing keys or wrong beam counts.
    """
    with open(path) as f:
        meta = json.load(f)
    check_metadata(meta)
    return meta


def check_metadata(meta: dict) -> None:
    """Validate the keys the simulator uses.

    Raises:
        ValueError: missing keys or inconsistent sizes.
    """
    for key in ("beam_altitude_angles", "beam_azimuth_angles", "lidar_to_sensor_transform", "imu_to_sensor_transform"):
        if key not in meta:
            raise ValueError("sensor metadata lacks %r" % key)
    h = len(meta["beam_altitude_angles"])
    if h < 1 or len(meta["beam_azimuth_angles"]) != h:
        raise ValueError("beam_altitude_angles and beam_azimuth_angles must have the same non-zero length")
    for key in ("lidar_to_sensor_transform", "imu_to_sensor_transform"):
        if len(meta[key]) != 16:
            raise ValueError("%s must have 16 values" % key)
    shifts = meta.get("data_format", {}).get("pixel_shift_by_row")
    if shifts is not None and len(shifts) != h:
        raise ValueError("pixel_shift_by_row must have one value per beam")


def transform_mm_to_m(values: list) -> np.ndarray:
    """Ouster's 16-value row-major transform in mm as a 4x4 matrix in m."""
    t = np.array(values, dtype=np.float64).reshape(4, 4)
    t[:3, 3] *= 1e-3
    return t


class Scan:
    """One simulated scan, destaggered, as (H, W) images (row 0 = top beam).

    Attributes:
        range_mm: uint32 range [mm], 0 = no return.
        reflectivity: uint16.
        ambient: uint16 near-IR.
        t_ns: (W,) uint32 time of each column since the scan timestamp [ns].
        hit: int16 id of what each ray hit (see :mod:`rbd_sim.raycast`).
        lut: Per axis (direction, offset) float32 images: xyz = range_m * direction + offset.
        nan_invalid: Whether zero ranges give NaN (else 0) coordinates.
    """

    __slots__ = ("range_mm", "reflectivity", "ambient", "t_ns", "hit", "lut", "nan_invalid")

    def xyz(self) -> np.ndarray:
        """(H, W, 3) float32 points in os_sensor [m], as ouster-ros computes them from range."""
        r = self.range_mm.astype(np.float32) * np.float32(1e-3)
        out = np.stack([r * d + o for d, o in self.lut], axis=-1)
        out[self.range_mm == 0] = np.nan if self.nan_invalid else 0.0
        return out


class Os1Model:
    """Beam geometry, noise and scan synthesis of an OS1.

    Args:
        metadata: Sensor metadata dict (see ``config/os1-32-u0.json``).
        columns: 512, 1024 or 2048.
        hz: 10 or 20 (2048 only at 10).
        range_noise_std: Standard deviation of the range noise [m].
        range_noise_max: Noise is clipped to +- this [m] (the OS1's +-30 mm accuracy).
        min_range: Returns closer than this read 0 [m].
        max_range: Returns farther than this read 0 [m].
        seed: Seed of the noise generator.
        nan_invalid: True: NaN xyz for zero range (ouster-ros >= v0.13); False: zeros.

    Raises:
        ValueError: unsupported mode or bad parameters.
    """

    def __init__(
        self,
        metadata: dict,
        columns: int = 1024,
        hz: int = 10,
        range_noise_std: float = 0.01,
        range_noise_max: float = 0.03,
        min_range: float = 0.3,
        max_range: float = 120.0,
        seed: int = 0,
        nan_invalid: bool = True,
    ) -> None:
        if (int(columns), int(hz)) not in VALID_MODES:
            raise ValueError("unsupported OS1 mode %sx%s (valid: %s)" % (columns, hz, VALID_MODES))
        if range_noise_std < 0 or range_noise_max < 0 or not 0 <= min_range < max_range:
            raise ValueError("noise must be >= 0 and 0 <= min_range < max_range")
        check_metadata(metadata)
        self.metadata = metadata
        self.columns, self.hz = int(columns), int(hz)
        self.noise_std, self.noise_max = float(range_noise_std), float(range_noise_max)
        self.min_range, self.max_range = float(min_range), float(max_range)
        self.nan_invalid = bool(nan_invalid)
        self.rng = np.random.default_rng(seed)
        self.altitudes = np.radians(np.array(metadata["beam_altitude_angles"], dtype=np.float64))
        self.azimuths = np.radians(np.array(metadata["beam_azimuth_angles"], dtype=np.float64))
        self.rows = h = len(self.altitudes)
        w = self.columns
        self.lidar_to_sensor = transform_mm_to_m(metadata["lidar_to_sensor_transform"])
        self.imu_to_sensor = transform_mm_to_m(metadata["imu_to_sensor_transform"])
        self.beam_offset = float(metadata.get("lidar_origin_to_beam_origin_mm", 0.0)) * 1e-3
        fmt = metadata.get("data_format", {})
        shifts = np.array(fmt.get("pixel_shift_by_row", [0] * h), dtype=np.int64)
        meta_w = int(fmt.get("columns_per_frame", w) or w)
        self.pixel_shift = np.round(shifts * (w / float(meta_w))).astype(np.int64)

        te = 2.0 * math.pi * (1.0 - np.arange(w) / float(w))  # (W,) encoder angle per column
        ang = te[None, :] - self.azimuths[:, None]  # (H, W)
        cphi = np.cos(self.altitudes)[:, None]
        d_lidar = np.stack(
            [np.cos(ang) * cphi, np.sin(ang) * cphi, np.broadcast_to(np.sin(self.altitudes)[:, None], ang.shape)],
            axis=-1,
        )
        n = self.beam_offset
        rot, trans = self.lidar_to_sensor[:3, :3], self.lidar_to_sensor[:3, 3]
        beam_origin = np.stack([n * np.cos(te), n * np.sin(te), np.zeros(w)], axis=-1)  # (W, 3)
        #: (H, W, 3) unit directions in os_sensor (staggered columns).
        self.directions = d_lidar.dot(rot.T)
        #: (W, 3) beam origin of each column in os_sensor [m].
        self.origins = beam_origin.dot(rot.T) + trans
        # ouster-sdk xyz LUT in os_sensor: xyz = range_m * lut_dir + lut_off (float32 per axis).
        off = (beam_origin[None, :, :] - n * d_lidar).dot(rot.T) + trans
        self._lut = [
            (np.ascontiguousarray(self.directions[:, :, i], np.float32), np.ascontiguousarray(off[:, :, i], np.float32))
            for i in range(3)
        ]
        self.raycaster = Raycaster(self.directions, self.origins)
        # Column timestamps [ns], ring numbers and a fixed ambient (near-IR) image.
        self.col_t_ns = (np.arange(w) * (1e9 / (self.hz * w))).astype(np.uint32)
        self._stagger_t = np.arange(w) / float(self.hz * w)  # firing time of each staggered column [s]
        amb_rng = np.random.default_rng(seed + 7919)
        self.ambient = amb_rng.integers(20, 120, size=(h, w)).astype(np.uint16)
        # Range noise: a seeded table of clipped normal samples [m]; each scan reads it from a
        # seeded random offset (drawing 65 k normals per scan would cost more than the cast).
        size = h * w
        table = self.rng.standard_normal(8 * size + 1).astype(np.float32) * np.float32(self.noise_std)
        self._noise = np.clip(table, -self.noise_max, self.noise_max)
        self._dest_cols = None
        if np.any(self.pixel_shift != 0):
            v = np.arange(w)[None, :]
            self._dest_cols = (v - self.pixel_shift[:, None]) % w  # out[u, v] = staggered[u, cols[u, v]]

    @property
    def period(self) -> float:
        """Scan period [s]."""
        return 1.0 / self.hz

    def scan(
        self,
        sensor_rotation: np.ndarray,
        sensor_translation: np.ndarray,
        world: object,
        t: float,
        velocity: np.ndarray = None,
        yaw_rate: float = 0.0,
    ) -> Scan:
        """Simulate one scan.

        Args:
            sensor_rotation: 3x3 rotation world <- os_sensor at the scan start.
            sensor_translation: os_sensor origin in the world at the scan start [m].
            world: A :class:`rbd_sim.world.World`.
            t: Time since the world epoch [s] (positions of people).
            velocity: Sensor velocity in the world [m/s]; with yaw_rate [rad/s] it moves the
                sensor while the columns are fired (motion distortion). None: standing still.
            yaw_rate: Turn rate about the world z axis [rad/s].

        Returns:
            A destaggered :class:`Scan`.
        """
        motion = None
        if velocity is not None or yaw_rate:
            vel = np.zeros(3) if velocity is None else np.asarray(velocity, dtype=np.float64)
            motion = (vel, float(yaw_rate), self._stagger_t)
        res = self.raycaster.cast(
            sensor_rotation,
            sensor_translation,
            world.floor_z,
            world.ceiling_z,
            world.all_boxes(),
            world.all_cylinders(t),
            self.max_range,
            motion,
        )
        return self.finish(res)

    def finish(self, res: object) -> Scan:
        """Turn ray-cast distances (staggered (H, W)) into a noisy, destaggered scan."""
        dist, hit = res.dist, res.hit
        h, w = dist.shape
        rng_m = dist + np.float32(self.beam_offset)
        if self.noise_std > 0:
            start = int(self.rng.integers(0, self._noise.size - h * w))
            rng_m += self._noise[start : start + h * w].reshape(h, w)
        rng_m *= np.float32(1000.0)
        valid = rng_m >= np.float32(self.min_range * 1000.0)
        valid &= rng_m <= np.float32(self.max_range * 1000.0)  # also drops inf (no hit)
        range_mm = np.zeros((h, w), dtype=np.uint32)
        np.rint(rng_m, out=rng_m)
        np.copyto(range_mm, rng_m, where=valid, casting="unsafe")
        refl_of = np.zeros(FIRST_PRIMITIVE_ID + len(res.primitives) + 1, dtype=np.uint16)
        refl_of[0], refl_of[1] = 30, 50  # floor, ceiling
        for i, p in enumerate(res.primitives):
            refl_of[FIRST_PRIMITIVE_ID + i] = p.reflectivity
        refl = refl_of[hit]  # NO_HIT (-1) indexes the trailing 0
        refl[~valid] = 0
        if self._dest_cols is not None:
            rows = np.arange(h)[:, None]
            range_mm, refl, hit = (
                range_mm[rows, self._dest_cols],
                refl[rows, self._dest_cols],
                hit[rows, self._dest_cols],
            )
        scan = Scan()
        scan.range_mm, scan.reflectivity, scan.hit = range_mm, refl, hit
        scan.lut = self._lut if self._dest_cols is None else self._destaggered_lut()
        scan.nan_invalid = self.nan_invalid
        scan.ambient = self.ambient
        scan.t_ns = self.col_t_ns
        return scan

    def _destaggered_lut(self) -> list:
        rows = np.arange(self.rows)[:, None]
        return [(d[rows, self._dest_cols], o[rows, self._dest_cols]) for d, o in self._lut]

    def pack(self, scan: Scan) -> bytes:
        """Serialise a scan as ouster-ros ``original`` points, row-major (row 0 first)."""
        h, w = scan.range_mm.shape
        pts = np.zeros((h, w), dtype=POINT_DTYPE)
        r = scan.range_mm.astype(np.float32)
        r *= np.float32(1e-3)
        zero = scan.range_mm == 0
        for name, (d, o) in zip(("x", "y", "z"), scan.lut):
            c = r * d
            c += o
            if scan.nan_invalid:
                c[zero] = np.nan
            else:
                c[zero] = 0.0
            pts[name] = c
        pts["pad"] = 1.0  # PCL's PointXYZ data[3]
        rr = np.maximum(r, np.float32(0.5))
        sig = scan.reflectivity.astype(np.float32) * np.float32(40.0)
        sig /= rr * rr
        pts["intensity"] = sig
        pts["t"] = scan.t_ns[None, :]
        pts["reflectivity"] = scan.reflectivity
        pts["ring"] = np.arange(h, dtype=np.uint16)[:, None]
        pts["ambient"] = scan.ambient
        pts["range"] = scan.range_mm
        return pts.tobytes()

    def is_dense(self, scan: Scan) -> bool:
        """ouster-ros >= v0.14: false when any point is NaN."""
        return not (scan.nan_invalid and bool(np.any(scan.range_mm == 0)))

    def metadata_json(self) -> str:
        """Metadata as the driver would publish on /ouster/metadata, for this mode."""
        meta = dict(self.metadata)
        meta["lidar_mode"] = "%dx%d" % (self.columns, self.hz)
        fmt = dict(meta.get("data_format", {}))
        fmt["columns_per_frame"] = self.columns
        fmt["column_window"] = [0, self.columns - 1]
        fmt["pixel_shift_by_row"] = [int(s) for s in self.pixel_shift]
        fmt["pixels_per_column"] = self.rows
        meta["data_format"] = fmt
        return json.dumps(meta, indent=4, sort_keys=True)
