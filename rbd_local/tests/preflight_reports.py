"""Preflight reports as the robot's bridge sends them (rbd_msgs/PreflightReport as rosbridge JSON).

Built by hand from the message definitions in ``src/rbd_msgs`` and the check lines of
rbd_preflight's README (names, values, hints of the kind the robot writes); rbd_local's own parser
is not used. :func:`msg_fields` reads the field names from the ``.msg`` files so a test can
prove these dicts have exactly the robot's fields.
"""

import os
import re

MSG_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                       "src", "rbd_msgs", "msg")


def msg_fields(name):
    """Field names of ``src/rbd_msgs/msg/<name>.msg`` in order (constants left out)."""
    fields = []
    with open(os.path.join(MSG_DIR, name + ".msg")) as fh:
        for line in fh:
            line = line.split("#", 1)[0].strip()
            m = re.match(r"^\S+\s+(\w+)$", line)
            if m:
                fields.append(m.group(1))
    return fields


def check(key, name, status, value, hint=""):
    return {"key": key, "name": name, "status": status, "value": value, "hint": hint}


def report(secs=1764084662, ready=False, checks=None):
    """A report of one observation ending at ``secs`` (default: one failing LiDAR check, one SKIP)."""
    if checks is None:
        checks = [
            check("a1_high_state", "A1 HighState", "PASS", "500.0 Hz (LCM tap 499.8 Hz)"),
            check("lidar_points", "LiDAR /ouster/points", "FAIL", "no message in 3.0 s",
                  "is ouster-ros running and the sensor powered? check the LiDAR's Ethernet link"),
            check("lidar_layout", "LiDAR cloud layout", "SKIP", "needs LiDAR /ouster/points"),
        ]
    return {
        "header": {"seq": 3, "stamp": {"secs": secs, "nsecs": 250000000}, "frame_id": ""},
        "ready": ready,
        "duration": 3.0,
        "checks": checks,
        "mounts": ["os_sensor: xyz (0.12, 0.0, 0.11) m, rpy (0.0, 0.0, 0.0) deg"],
        "mounts_file": "/opt/robodog/mounts.yaml",
    }


def all_pass(secs=1764084700):
    return report(secs, True, [check("a1_high_state", "A1 HighState", "PASS", "500.0 Hz"),
                               check("lidar_points", "LiDAR /ouster/points", "PASS", "10.0 Hz, 0.05 s old")])
