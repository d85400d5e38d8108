"""The checks of the ROS graph: TF, the zone, the pose, the map, the floor, the bridge, the hosts' clocks."""

from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from rbd_geometry.rotation import quat_to_matrix
from rbd_preflight.facts import FEET, FOOT_RADIUS
from rbd_preflight.floor import floor_check
from rbd_preflight.model import FAIL, PASS, SKIP, Limits, Observation
from rbd_preflight.rates import fmt_rate, rate_check
from rbd_preflight.render import format_mount


def _check_frame(obs: Observation, frame: str, hint: str) -> Tuple[str, str, str]:
    t = obs.frames.get(frame)
    if t is None or isinstance(t, str):
        return FAIL, "%s -> %s missing%s" % (obs.base_frame, frame, (": " + t) if t else ""), hint
    return PASS, format_mount(t), ""


def check_tf_lidar(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """TF base_link -> os_sensor (the LiDAR's mount)."""
    return _check_frame(obs, obs.lidar_frame, "robot_state_publisher with rbd_description's robot_description "
                        "(a1_urdf + mounts.yaml) must run")


def check_tf_zed2(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """TF base_link -> zed2_camera_center (the ZED2's mount)."""
    return _check_frame(obs, obs.zed2_frame, "robot_state_publisher with rbd_description's robot_description "
                        "(a1_urdf + mounts.yaml) must run")


def tf_clashes(edges: Sequence[Tuple[str, str, str, bool]]) -> List[str]:
    """Frames with two parents, or with one parent from two publishers: one text each."""
    by_child = {}  # child -> {parent: {publisher}}
    for parent, child, publisher, _static in edges:
        by_child.setdefault(child.lstrip("/"), {}).setdefault(parent.lstrip("/"), set()).add(publisher)
    out = []
    for child in sorted(by_child):
        parents = by_child[child]
        if len(parents) > 1:
            out.append("%s has %d parents: %s" % (child, len(parents), ", ".join(
                "%s (%s)" % (p, ", ".join(sorted(pubs))) for p, pubs in sorted(parents.items()))))
        else:
            ((parent, pubs),) = parents.items()
            if len(pubs) > 1:
                out.append("%s -> %s published by %d nodes: %s" % (parent, child, len(pubs), ", ".join(sorted(pubs))))
    return out


def check_tf_parents(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """Every TF frame has one parent and one publisher."""
    if not obs.tf_edges:
        return FAIL, "no transforms on /tf or /tf_static", "nothing publishes TF: start the robot stack"
    clashes = tf_clashes(obs.tf_edges)
    frames = len({e[1] for e in obs.tf_edges})
    if clashes:
        return (FAIL, "; ".join(clashes),
                "one publisher per frame: zed-ros-wrapper publish_urdf:=false and pos_tracking publish_tf/"
                "publish_map_tf false (robot.launch drivers:=true sets them); stop the other publisher")
    return PASS, "%d frames, each with one parent and one publisher" % frames, ""


def check_zone(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """/rbd_lidar/state fresh, not stale, no error."""
    s = obs.stream("zone")
    if s.count == 0:
        return FAIL, "no /rbd_lidar/state in %.1f s" % obs.duration, "rbd_lidar is not running"
    age = s.age(obs.now)
    last = obs.zone_last or {}
    value = "%s, last %.2f s ago" % (fmt_rate(s), age)
    if last.get("stale"):
        return FAIL, value + ", stale", "rbd_lidar gets no valid cloud: see its log and the /ouster/points lines"
    if last.get("error"):
        return FAIL, value + ", error: %s" % last["error"], "rbd_lidar rejects the cloud: see the layout line"
    if age > lim.zone_max_age:
        return FAIL, value + " (stale after %.1f s)" % lim.zone_max_age, "rbd_lidar stalls: see its log"
    occupied = last.get("collision")
    return PASS, value + (", zone OCCUPIED (%s points)" % "/".join(str(p) for p in last.get("points", ()))
                          if occupied else ", zone clear"), ""


def check_pose(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """/rbd_localization/pose fresh at >= 10 Hz."""
    return rate_check(obs, "pose", "/rbd_localization/pose", lim.pose_min_rate, lim.pose_max_age, 0.5, lim.max_future,
                       "no localization pose: rbd_localization (EKF + map correction) is not running or has no input",
                       "localization pose slower than 10 Hz: the EKF lacks input (IMU, ZED2) or the CPU is overloaded",
                       "pose stamps are not ROS time")


LOCALIZE_HINT = ("the start search in the loaded map has not converged: place the robot within 1 m / 45 deg "
                 "of the map's home (or give home_x/home_y/home_yaw), keep it standing for 5 s; if it never "
                 "converges the map is of another place or the robot sees little of it (map_correction's log "
                 "and its 'Map correction' diagnostics say why)")


def localization_mode(mode: Optional[str]) -> Optional[bool]:
    """From the map correction's diagnostics ``mode``: True in a loaded map, False mapping, None unknown."""
    if mode is None:
        return None
    return mode.startswith("localization")


def check_localized(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """With a loaded map: /rbd_localization/localized is true (n/a without a map)."""
    in_map = localization_mode(obs.map_mode)
    if in_map is False:
        note = "; initial mapping still running" if obs.localized is False else ""
        return PASS, "n/a: no map loaded (map correction in %s mode%s)" % (obs.map_mode, note), ""
    if obs.localized is None:
        if in_map is None:
            return PASS, "n/a: no map loaded (no /rbd_localization/localized, no map correction diagnostics)", ""
        value = "no /rbd_localization/localized in %.1f s (map correction in %s mode)" % (obs.duration, obs.map_mode)
        return FAIL, value, "map_correction_node publishes it latched from its start: see its log"
    where = " (%s)" % obs.map_mode if obs.map_mode else ""
    if obs.localized:
        return PASS, "localized in the map%s" % where, ""
    return FAIL, "not localized in the map%s" % where, LOCALIZE_HINT


def check_floor(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """The floor the LiDAR sees lies where the mounts and the legs put it."""
    t = obs.frames.get(obs.lidar_frame)
    if obs.cloud_xyz is None or t is None or isinstance(t, str):
        return SKIP, "no cloud or no %s transform" % obs.lidar_frame, ""
    (x, y, z), q = t
    pts = np.asarray(obs.cloud_xyz, dtype=float).reshape(-1, 3).dot(quat_to_matrix(q).T) + np.array([x, y, z])
    feet = [obs.frames.get(f) for f in FEET]
    contacts = None
    if all(f is not None and not isinstance(f, str) for f in feet):
        contacts = np.array([f[0] for f in feet], dtype=float) - np.array([0.0, 0.0, FOOT_RADIUS])
    status, value, hint, _numbers = floor_check(pts, contacts, lim)
    return status, value, hint


def check_bridge(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """rbd_bridge up and accepting WebSocket connections; who is connected."""
    b = obs.bridge
    if b is None or not b.get("node"):
        return FAIL, "rbd_bridge is not running", "the laptop app cannot connect: start the robot stack"
    where = "ws://%s:%s" % (b.get("host"), b.get("port"))
    if not b.get("listening"):
        return FAIL, "%s not answering: %s" % (where, b.get("error") or "?"), (
            "check rbd_bridge's log, bridge_address/bridge_port and the firewall")
    clients = b.get("clients")
    if clients:
        who = "%d client(s): %s" % (len(clients), ", ".join(clients))
    elif clients is not None or b.get("client_count") == 0:
        who = "no clients connected"
    else:
        who = "%s client(s)" % b.get("client_count", "?")
    return PASS, "%s listening, %s" % (where, who), ""


def clock_spread(clocks: Dict[str, Tuple[float, float, str]]) -> Tuple[float, Tuple[str, str]]:
    """Worst case between two hosts: |offset_i - offset_j| + uncertainty_i + uncertainty_j [s], and the pair."""
    worst, pair = 0.0, ("", "")
    hosts = sorted(clocks)
    for i, a in enumerate(hosts):
        for b in hosts[i + 1:]:
            (oa, ua, _), (ob, ub, _) = clocks[a], clocks[b]
            w = abs(oa - ob) + ua + ub
            if w > worst:
                worst, pair = w, (a, b)
    return worst, pair


def check_clocks(obs: Observation, lim: Limits) -> Tuple[str, str, str]:
    """The clocks of all ROS hosts agree within 50 ms (only when the graph spans hosts)."""
    if obs.clocks is None:
        return SKIP, "not measured", ""
    errors = {h: v for h, v in obs.clocks.items() if isinstance(v, str)}
    good = {h: v for h, v in obs.clocks.items() if not isinstance(v, str)}
    if len(obs.clocks) <= 1:
        return PASS, "one ROS host (%s): nothing to compare" % (", ".join(obs.clocks) or "-"), ""
    detail = ", ".join("%s %+.1f +- %.1f ms" % (h, 1000 * o, 1000 * u) for h, (o, u, _s) in sorted(good.items()))
    if errors:
        return (FAIL, "cannot read the clock of %s%s" % (
            "; ".join("%s (%s)" % kv for kv in sorted(errors.items())), ("; " + detail) if detail else ""),
            "preflight reads a host's clock from the HTTP Date of its roslaunch/rospy XML-RPC servers: start "
            "that host's nodes with roslaunch, and sync the clocks with chrony (rbd_bringup README)")
    worst, (a, b) = clock_spread(good)
    value = "%d hosts: %s (vs this host)" % (len(good), detail)
    if worst > lim.clock_max_skew:
        return (FAIL, value + "; %s vs %s up to %.0f ms" % (a, b, 1000 * worst),
                "sync the clocks: chrony with the Jetson as server (rbd_bringup README, Clocks); TF and the "
                "staleness checks compare stamps across hosts")
    return PASS, value, ""
