"""The checks of the robot's sensors and links: A1, e-stop chain, LiDAR cloud and IMU, ZED2 pose."""

import math
from typing import Optional, Sequence, Tuple

import numpy as np

from rbd_preflight.facts import (
    A1_DIAG_NAME,
    A1_HIGH_CMD_SIZE,
    A1_STATE_SIZES,
    DATATYPE_NAMES,
    OS1_ROWS,
    OS1_WIDTHS,
    OUSTER_POINT,
    OUSTER_POINT_STEP,
    size_name,
)
from rbd_preflight.model import FAIL, PASS, SKIP, Limits, Observation
from rbd_preflight.rates import diag_float, fmt_rate, last_diag, rate_check


def check_a1_state(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """HighState arriving at the driver, at the SDK's rate."""
    diag = last_diag(obs)
    if diag is None:
        return (FAIL, "no '%s' diagnostics in %.1f s" % (A1_DIAG_NAME, obs.duration),
                "start the robot stack (roslaunch rbd_bringup robot.launch): rbd_a1_driver is not running")
    rate = diag_float(diag, "high_state_rate") or 0.0
    value = "%.0f Hz at the driver" % rate
    if obs.wire is not None:
        span = max(obs.wire.get("span", 0.0), 1e-3)
        known = sum(n for size, n in obs.wire["state_sizes"].items() if size in A1_STATE_SIZES)
        value += ", %.0f Hz on the wire (%s)" % (known / span, obs.wire.get("url", "LCM"))
    if rate < lim.a1_state_min_rate:
        return (FAIL, value + " (need >= %.0f Hz)" % lim.a1_state_min_rate,
                "no usable HighState: is the SDK's lcm_server_high running on the driver's LCM URL (%s)? "
                "is the A1 on and reachable (192.168.123.161)?" % diag["values"].get("lcm_url", "?"))
    return PASS, value, ""


def check_a1_layout(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """The SDK layout the driver detected; no packets of an unknown size."""
    diag = last_diag(obs)
    if diag is None and obs.wire is None:
        return SKIP, "no driver diagnostics, no LCM tap", ""
    seen = {}  # size -> count of HighStates of an unknown size
    if obs.wire is not None:
        seen = {s: n for s, n in obs.wire["state_sizes"].items() if s not in A1_STATE_SIZES}
    dropped = 0
    if len(obs.a1_diag) >= 2:
        counts = [diag_float(d, "unknown_size_packets") or 0.0 for d in obs.a1_diag]
        dropped = int(counts[-1] - counts[0])
    layout = diag["values"].get("sdk_layout", "unknown") if diag else "unknown"
    source = diag["values"].get("sdk_layout_source", "?") if diag else "?"
    size = int(diag_float(diag, "high_state_size") or 0) if diag else 0
    if seen or dropped > 0:
        sizes = ", ".join("%s x%d" % (size_name(s), n) for s, n in sorted(seen.items())) if seen else (
            "%d dropped by the driver, last size %s" % (dropped, size_name(size)))
        return (FAIL, "HighState of an unknown size: %s; driver layout %s" % (sizes, layout),
                "known: 265 B (SDK v3.3/v3.3.1), 1025 B (SDK 3.3.3/3.3.4): build lcm_server_high from one of "
                "them, and run only one LCM server on this URL")
    if layout not in ("3.3", "3.3.4"):
        return (FAIL, "no layout detected (last HighState %s)" % (size_name(size) if size else "none"),
                "no usable HighState yet: see the A1 HighState line")
    expected_size = {"3.3": 265, "3.3.4": 1025}[layout]
    how = "forced" if source == "forced" else "by size"
    return PASS, "SDK %s, HighState %d B (%s)" % (layout, expected_size, how), ""


def check_a1_cmd(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """HighCmd going out at the driver's send rate."""
    diag = last_diag(obs)
    if diag is None:
        return SKIP, "no driver diagnostics (see A1 HighState)", ""
    rate = diag_float(diag, "high_cmd_rate") or 0.0
    value = "%.0f Hz sent" % rate
    if obs.wire is not None:
        span = max(obs.wire.get("span", 0.0), 1e-3)
        cmds = obs.wire["cmd_sizes"]
        value += ", %.0f Hz of %d B on the wire" % (cmds.get(A1_HIGH_CMD_SIZE, 0) / span, A1_HIGH_CMD_SIZE)
        odd = {s: n for s, n in cmds.items() if s != A1_HIGH_CMD_SIZE}
        if odd:
            return (FAIL, value + "; also HighCmd of %s" % ", ".join("%d B x%d" % kv for kv in sorted(odd.items())),
                    "another program sends on LCM_High_Cmd: stop it (the A1 takes every command)")
    if rate < lim.a1_cmd_min_rate:
        return (FAIL, value + " (need >= %.0f Hz)" % lim.a1_cmd_min_rate,
                "rbd_a1_driver is not sending: see its log (rosnode info /rbd_a1_driver); lcm_server_high "
                "exits after 20 ms without a command")
    return PASS, value, ""


def check_estop(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """rbd_controller's e-stop signal at 10 Hz, the driver's watchdog armed."""
    s = obs.stream("estop")
    diag = last_diag(obs)
    armed = diag is not None and diag["values"].get("estop_gate_armed") == "true"
    value = "signal %s, driver gate %s" % (fmt_rate(s), "armed" if armed else "NOT armed")
    if s.count == 0 or s.rate() < lim.estop_min_rate:
        return (FAIL, value + " (need >= %.0f Hz)" % lim.estop_min_rate,
                "rbd_controller is not republishing /rbd_controller/estop: is it running?")
    if diag is None:
        return FAIL, value + " (no driver diagnostics)", "rbd_a1_driver is not running"
    if not armed:
        return (FAIL, value, "the driver has not armed its e-stop watchdog: ~estop_timeout must be > 0 and "
                "the driver must receive /rbd_controller/estop")
    return PASS, value, ""


def check_lidar_cloud(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """/ouster/points arriving at the mode's rate, fresh, in ROS time."""
    hz = lim.lidar_default_hz
    if obs.lidar_mode and "x" in obs.lidar_mode:
        try:
            hz = float(obs.lidar_mode.split("x")[1])
        except ValueError:
            pass
    status, value, hint = rate_check(
        obs, "points", "/ouster/points", lim.lidar_rate_fraction * hz, lim.lidar_max_periods / hz, lim.lidar_max_lag,
        lim.max_future,
        "no cloud: is ouster-ros running (ouster_ns:=ouster, proc_mask with PCL) and the OS1 reachable?",
        "cloud slower than the %s mode: the Jetson or the OS1's link is overloaded" % (obs.lidar_mode or "10 Hz"),
        "cloud stamps are not ROS time: ouster-ros timestamp_mode:=TIME_FROM_ROS_TIME (or sync the clocks)")
    if obs.lidar_mode:
        value += " (mode %s)" % obs.lidar_mode
    return status, value, hint


def check_lidar_layout(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """The last cloud has ouster-ros' 48-byte point, 32 rows, organised, little-endian, in os_sensor."""
    c = obs.cloud
    if c is None:
        return SKIP, "no cloud to check (see /ouster/points)", ""
    fields = {f[0]: f for f in c["fields"]}
    problems = []
    for name, (offset, types) in sorted(OUSTER_POINT.items(), key=lambda kv: kv[1][0]):
        f = fields.get(name)
        if f is None:
            problems.append("no field %s" % name)
        elif f[1] != offset or f[2] not in types or f[3] != 1:
            problems.append("%s %s@%d (need %s@%d)" % (name, DATATYPE_NAMES.get(f[2], f[2]), f[1],
                                                      DATATYPE_NAMES[types[0]], offset))
    if c["point_step"] != OUSTER_POINT_STEP:
        problems.append("point_step %d (need %d)" % (c["point_step"], OUSTER_POINT_STEP))
    if c["is_bigendian"]:
        problems.append("big-endian")
    if c["height"] != OS1_ROWS:
        problems.append("%d rows (need %d: organized:=true, v_reduction 1)" % (c["height"], OS1_ROWS))
    if c["width"] not in OS1_WIDTHS:
        problems.append("%d columns (need one of %s)" % (c["width"], "/".join(str(w) for w in OS1_WIDTHS)))
    if c["row_step"] != c["point_step"] * c["width"] or c["data_len"] != c["row_step"] * c["height"]:
        problems.append("sizes do not add up (row_step %d, %d B of data)" % (c["row_step"], c["data_len"]))
    if c["frame_id"] != obs.lidar_frame:
        problems.append("frame %r (need %s)" % (c["frame_id"], obs.lidar_frame))
    shape = "%d x %d, %d B/point" % (c["height"], c["width"], c["point_step"])
    if problems:
        return (FAIL, shape + ": " + "; ".join(problems),
                "run ouster-ros with point_type:=original organized:=true destagger:=true point_cloud_frame:=os_sensor "
                "(robot.launch drivers:=true sets them)")
    return PASS, shape + ", ouster-ros original layout, frame %s" % c["frame_id"], ""


def check_lidar_imu(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """/ouster/imu at 100 Hz."""
    return rate_check(obs, "imu", "/ouster/imu", lim.imu_min_rate, 0.5, lim.imu_max_lag, lim.max_future,
                       "no OS1 IMU: ouster-ros proc_mask must contain IMU",
                       "OS1 IMU slower than 100 Hz: UDP packets lost (the OS1's link, udp_dest)",
                       "IMU stamps are not ROS time: ouster-ros timestamp_mode:=TIME_FROM_ROS_TIME")


def covariance_problem(cov: Sequence[float], lim: Limits) -> Optional[str]:
    """A text if a 6 x 6 pose covariance is not sane (NaN, asymmetric, negative or huge variances, all zero)."""
    c = np.asarray(cov, dtype=float)
    if c.size != 36:
        return "covariance of %d numbers" % c.size
    c = c.reshape(6, 6)
    if not np.all(np.isfinite(c)):
        return "covariance has NaN/inf"
    if not np.allclose(c, c.T, atol=1e-9 + 1e-6 * np.abs(c).max()):
        return "covariance not symmetric"
    diag = np.diag(c)
    if np.any(diag < 0):
        return "negative variance"
    if not np.any(diag > 0):
        return "covariance all zero"
    if np.any(diag[:3] > lim.zed2_max_position_var) or np.any(diag[3:] > lim.zed2_max_orientation_var):
        return "variance too large (position sd %.2f m, orientation sd %.2f rad)" % (
            math.sqrt(diag[:3].max()), math.sqrt(diag[3:].max()))
    return None


def check_zed2(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """ZED2 pose at its grab rate, stamped in ROS time, with a sane covariance."""
    status, value, hint = rate_check(
        obs, "zed2", "/zed2/zed_node/pose_with_covariance", lim.zed2_min_rate, 0.5, lim.zed2_max_lag, lim.max_future,
        "no ZED2 pose: is zed-ros-wrapper running (camera_name zed2, positional tracking on) and the camera on USB 3?",
        "ZED2 pose slower than 10 Hz: the Jetson is overloaded (grab_frame_rate 15)",
        "ZED2 stamps are not this host's ROS time: sync the clocks (chrony)")
    if status != PASS:
        return status, value, hint
    problem = covariance_problem(obs.zed2_covariance, lim) if obs.zed2_covariance is not None else "no covariance"
    if problem:
        return FAIL, value + ", " + problem, "the ZED2's tracking is lost or not initialised: restart its tracking"
    sd = np.sqrt(np.diag(np.asarray(obs.zed2_covariance, dtype=float).reshape(6, 6)))
    return PASS, value + ", sd %.3f m / %.3f rad" % (sd[:3].max(), sd[3:].max()), ""
