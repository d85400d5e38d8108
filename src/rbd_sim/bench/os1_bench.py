"""Benchmark of the simulated OS1-32: ms per scan and real-time factor at 512/1024/2048 columns.

Run by bench/run OUTDIR (or: python3 bench/os1_bench.py OUTDIR). For each world (lab, fair)
and column count, runs the per-scan work of os1_sim (ray cast with a moving, tilting robot and
walking people, noise, ouster-ros packing, and PointCloud2 serialisation) and prints one JSON
line per case; real_time_factor = scan period / CPU time per scan (> 1: faster than real
time). Results also go to OUTDIR/os1_sim.json.
"""

import io
import json
import math
import os
import sys
import time

import numpy as np

from rbd_geometry.rotation import rpy_to_matrix
from rbd_sim import os1
from rbd_sim.world_file import load_world, resolve_world_path

HERE = os.path.dirname(os.path.abspath(__file__))
WORLDS = os.path.join(HERE, "..", "worlds")


def serialiser() -> object:
    """PointCloud2 serialisation (what rospy does per publish), or None without ROS messages."""
    try:
        from sensor_msgs.msg import PointCloud2, PointField
    except ImportError:
        return None
    fields = [PointField(n, o, d, 1) for n, o, d in os1.POINT_FIELDS]

    def run(data: bytes, h: int, w: int) -> int:
        msg = PointCloud2(height=h, width=w, fields=fields, point_step=48, row_step=48 * w, data=data)
        buf = io.BytesIO()
        msg.serialize(buf)
        return buf.tell()

    return run


def bench(world_name: str, columns: int, hz: int, scans: int, ser: object) -> dict:
    """Time the per-scan work for one world and mode; returns the result record."""
    world = load_world(resolve_world_path(world_name, WORLDS))
    meta = os1.load_metadata(os1.DEFAULT_METADATA)
    model = os1.Os1Model(meta, columns, hz, seed=1)
    times, cpu = [], []
    for k in range(scans + 3):
        t = k / float(hz)
        rot = rpy_to_matrix(0.05 * math.sin(t), 0.08 * math.sin(1.3 * t), 0.4 * t)
        pos = np.array([0.5 * math.sin(0.2 * t), 0.3 * math.cos(0.2 * t), 0.35])
        start, cstart = time.perf_counter(), time.process_time()
        scan = model.scan(rot, pos, world, t)
        data = model.pack(scan)
        if ser is not None:
            ser(data, 32, columns)
        if k >= 3:  # warm-up excluded
            times.append(time.perf_counter() - start)
            cpu.append(time.process_time() - cstart)
    # CPU time is what the simulator takes from the machine; wall time also counts the waits
    # for a core on a shared, loaded machine.
    ms = 1e3 * float(np.median(cpu))
    wall = 1e3 * float(np.median(times))
    return {
        "bench": "os1_sim_scan",
        "world": world_name,
        "columns": columns,
        "hz": hz,
        "scans": scans,
        "cpu_ms_per_scan_median": round(ms, 2),
        "wall_ms_per_scan_median": round(wall, 2),
        "wall_ms_per_scan_p90": round(1e3 * float(np.percentile(times, 90)), 2),
        "real_time_factor": round(1e3 / hz / ms, 1),
        "real_time_factor_wall": round(1e3 / hz / wall, 1),
        "cpu_share_of_one_core": round(ms * hz / 1e3, 3),
        "includes_serialisation": ser is not None,
    }


def main() -> int:
    """Run all cases, print JSON lines, write OUTDIR/os1_sim.json."""
    if len(sys.argv) != 2:
        print("usage: os1_bench.py OUTDIR", file=sys.stderr)
        return 2
    out_dir = sys.argv[1]
    os.makedirs(out_dir, exist_ok=True)
    ser = serialiser()
    results = []
    for world_name in ("lab", "fair"):
        for columns, hz in ((512, 10), (1024, 10), (2048, 10), (1024, 20)):
            r = bench(world_name, columns, hz, 40, ser)
            print(json.dumps(r, sort_keys=True), flush=True)
            results.append(r)
    with open(os.path.join(out_dir, "os1_sim.json"), "w") as f:
        json.dump(results, f, indent=2, sort_keys=True)
    worst = min(r["real_time_factor"] for r in results if r["columns"] == 2048)
    worst_wall = min(r["real_time_factor_wall"] for r in results if r["columns"] == 2048)
    print("os1_sim: 32x2048 @ 10 Hz real-time factor %.1f CPU, %.1f wall (worst world)" % (worst, worst_wall))
    return 0 if worst >= 1.0 else 1


if __name__ == "__main__":
    sys.exit(main())
