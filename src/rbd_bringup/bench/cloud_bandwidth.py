#!/usr/bin/env python3
"""Bytes per second of /ouster/points vs the audience's /ouster/points_decimated, simulated OS1.

For each OS1 mode (default 1024x10 and 2048x10) it starts a private rosmaster, rbd_sim's os1_sim
in the lab world (robot standing at the origin: fixed_base_pose) and rbd_bringup's
cloud_decimator with its defaults, subscribes both topics without deserialising (AnyMsg) and
counts the serialised bytes (+4 length bytes per message, as TCPROS sends them) over a window.
Also reports the decimator's CPU (% of one core, /proc) in the same window.

Usage: cloud_bandwidth.py OUTDIR [--seconds 10] [--modes 1024x10,2048x10]
Writes OUTDIR/cloud_bandwidth.json and prints one row per mode.
"""

import argparse
import json
import os
import sys
import time

from rbd_testkit import RosEnv, stop_process


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process [s]."""
    with open("/proc/%d/stat" % pid) as fh:
        fields = fh.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / float(os.sysconf("SC_CLK_TCK"))


class Counter:
    """Bytes and messages of one topic."""

    def __init__(self, topic: str) -> None:
        import rospy

        self.bytes = 0
        self.msgs = 0
        self.counting = False
        rospy.Subscriber(topic, rospy.AnyMsg, self.on_msg, queue_size=5, buff_size=1 << 25)

    def on_msg(self, msg: object) -> None:
        """Count one serialised message (while counting)."""
        if self.counting:
            self.bytes += len(msg._buff) + 4
            self.msgs += 1


def run_mode(columns: int, hz: int, seconds: float, ros: RosEnv) -> dict:
    """Measure one mode against the private master; returns the row."""
    import rospy

    procs = [ros.start(["rosrun", "rbd_sim", "os1_sim", "_world:=lab", "_lidar_columns:=%d" % columns,
                        "_lidar_hz:=%d" % hz, "_fixed_base_pose:=[0.0, 0.0, 0.28, 0.0, 0.0, 0.0]"])]
    try:
        dec = ros.start(["rosrun", "rbd_bringup", "cloud_decimator", "points:=/ouster/points",
                         "points_decimated:=/ouster/points_decimated"])
        procs.append(dec)
        full, thin = Counter("/ouster/points"), Counter("/ouster/points_decimated")
        deadline = time.monotonic() + 60
        full.counting = thin.counting = True
        while (full.msgs < 3 or thin.msgs < 3) and time.monotonic() < deadline:
            time.sleep(0.1)
        if thin.msgs < 3:
            raise RuntimeError("no decimated clouds (logs in %s)" % ros.home)
        full.counting = thin.counting = False
        full.bytes = full.msgs = thin.bytes = thin.msgs = 0
        cpu0, t0 = cpu_seconds(dec.pid), time.monotonic()
        full.counting = thin.counting = True
        time.sleep(seconds)
        full.counting = thin.counting = False
        dt = time.monotonic() - t0
        cpu = (cpu_seconds(dec.pid) - cpu0) / dt
        row = {"mode": "%dx%d" % (columns, hz), "seconds": round(dt, 2),
               "points_Bps": full.bytes / dt, "points_hz": full.msgs / dt,
               "decimated_Bps": thin.bytes / dt, "decimated_hz": thin.msgs / dt,
               "points_Mbit_s": 8e-6 * full.bytes / dt, "decimated_Mbit_s": 8e-6 * thin.bytes / dt,
               "points_bytes_per_cloud": full.bytes / max(1, full.msgs),
               "decimated_bytes_per_cloud": thin.bytes / max(1, thin.msgs),
               "ratio": (full.bytes / float(thin.bytes)) if thin.bytes else None,
               "decimator_cpu_pct": 100.0 * cpu}
        rospy.loginfo("measured %s", row["mode"])
        return row
    finally:
        for p in reversed(procs):
            stop_process(p)


def main() -> int:
    """Measure every mode, print the table, write the JSON."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--modes", default="1024x10,2048x10")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    ros = RosEnv()
    rows = []
    try:
        ros.use_in_this_process()
        import rospy

        rospy.init_node("cloud_bandwidth", anonymous=True, disable_signals=True)
        for mode in args.modes.split(","):
            columns, hz = (int(v) for v in mode.split("x"))
            rows.append(run_mode(columns, hz, args.seconds, ros))
    finally:
        ros.close()
    print("cloud_bandwidth: simulated OS1 (lab world), cloud_decimator defaults, %.0f s per mode" % args.seconds)
    print("%-8s %14s %10s %11s %16s %8s %10s %7s %14s" % (
        "mode", "points Mbit/s", "points Hz", "kB/cloud", "decimated Mbit/s", "dec. Hz", "kB/cloud", "ratio",
        "decimator CPU"))
    for r in rows:
        print("%-8s %14.1f %10.1f %11.1f %16.2f %8.1f %10.1f %7.1f %13.1f%%" % (
            r["mode"], r["points_Mbit_s"], r["points_hz"], r["points_bytes_per_cloud"] / 1e3, r["decimated_Mbit_s"],
            r["decimated_hz"], r["decimated_bytes_per_cloud"] / 1e3, r["ratio"] or float("nan"),
            r["decimator_cpu_pct"]))
    print("(the simulated OS1 must keep up with its rate for the Mbit/s to be the sensor's: check the Hz columns)")
    with open(os.path.join(args.out, "cloud_bandwidth.json"), "w") as fh:
        json.dump(rows, fh, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
