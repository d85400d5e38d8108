"""The table of checks and its evaluation: one row per check, SKIP when a needed check failed."""

from typing import List, Optional

from rbd_preflight.graph_checks import (
    check_bridge,
    check_clocks,
    check_floor,
    check_localized,
    check_pose,
    check_tf_lidar,
    check_tf_parents,
    check_tf_zed2,
    check_zone,
)
from rbd_preflight.model import FAIL, PASS, SKIP, Limits, Observation, Row
from rbd_preflight.sensor_checks import (
    check_a1_cmd,
    check_a1_layout,
    check_a1_state,
    check_estop,
    check_lidar_cloud,
    check_lidar_imu,
    check_lidar_layout,
    check_zed2,
)

#: (key, name, check, keys it needs: SKIP when one of them did not pass)
CHECKS = [
    ("a1_state", "A1 HighState", check_a1_state, ()),
    ("a1_layout", "A1 SDK layout", check_a1_layout, ()),
    ("a1_cmd", "A1 HighCmd", check_a1_cmd, ()),
    ("estop", "E-stop chain", check_estop, ()),
    ("lidar_cloud", "LiDAR /ouster/points", check_lidar_cloud, ()),
    ("lidar_layout", "LiDAR cloud layout", check_lidar_layout, ()),
    ("lidar_imu", "LiDAR /ouster/imu", check_lidar_imu, ()),
    ("zed2", "ZED2 pose", check_zed2, ()),
    ("tf_lidar", "TF base_link->os_sensor", check_tf_lidar, ()),
    ("tf_zed2", "TF base_link->ZED2", check_tf_zed2, ()),
    ("tf_parents", "TF one parent per frame", check_tf_parents, ()),
    ("zone", "LiDAR zone state", check_zone, ("lidar_cloud", "lidar_layout", "tf_lidar")),
    ("pose", "Localization pose", check_pose, ()),
    ("localized", "Localized in the map", check_localized, ()),
    ("floor", "Floor vs mounts", check_floor, ("lidar_layout", "tf_lidar")),
    ("bridge", "Bridge", check_bridge, ()),
    ("clocks", "Clocks of ROS hosts", check_clocks, ()),
]


def evaluate(obs: Observation, limits: Optional[Limits] = None) -> List[Row]:
    """Run every check on ``obs``; one :class:`Row` per check, in table order."""
    lim = limits or Limits()
    rows = []  # type: List[Row]
    names = {key: name for key, name, _f, _n in CHECKS}
    done = {}  # type: Dict[str, str]
    for key, name, check, needs in CHECKS:
        blocked = [n for n in needs if done.get(n) != PASS]
        if blocked:
            row = Row(key, name, SKIP, "needs: %s" % ", ".join(names[n] for n in blocked))
        else:
            try:
                status, value, hint = check(obs, lim)
            except Exception as exc:  # a bug in one check must not hide the others
                status, value, hint = FAIL, "check failed: %r" % (exc,), "report this preflight bug"
            row = Row(key, name, status, value, hint)
        done[key] = row.status
        rows.append(row)
    return rows
