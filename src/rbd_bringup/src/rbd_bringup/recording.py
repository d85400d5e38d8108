"""Recordings of the robot's real inputs and their replay, free of ROS (issue 16, "Replay").

A recording is one directory:

- ``sensors.bag``: rosbag of the sensor drivers' ROS topics (:data:`ROS_TOPICS`: the OS1 cloud,
  IMU and metadata, the ZED2 pose, and ``/tf_static`` for the drivers' own static frames);
- ``a1_highstate.lcmlog``: LCM's own event log (``lcm-logger``) of ``LCM_High_State``, the A1's
  state packets as the SDK's ``lcm_server_high`` sends them;
- ``recording.yaml``: what was recorded, where from, how long.

``rosrun rbd_bringup record DIR`` makes one (``make demo`` leaves one in ``demo-output/recording``);
``roslaunch rbd_bringup robot.launch replay:=DIR`` runs the robot stack on it: ``rosbag play
--clock`` and ``lcm-logplayer`` feed the stack, which runs on the bag's clock. During a replay the
driver's LCM URL is a private one (:func:`private_lcm_url_problem`): multicast with ``ttl=0`` (the
packets never leave this host) on a port other than the SDK's 7667, so no HighCmd reaches a live
``lcm_server_high``. Only the commands and the rules live here; the nodes ``record`` and
``replay`` run them.
"""

import xml.etree.ElementTree as ET
from typing import Dict, Iterable, List, Optional, Sequence, Tuple
from urllib.parse import parse_qs, urlparse

BAG = "sensors.bag"
LCM_LOG = "a1_highstate.lcmlog"
MANIFEST = "recording.yaml"
#: The sensor drivers' topics (ouster-ros with ouster_ns:=ouster, zed-ros-wrapper zed2): what the
#: robot stack reads from outside. Everything else our stack computes again on replay.
ROS_TOPICS = (
    "/ouster/points",
    "/ouster/imu",
    "/ouster/metadata",
    "/zed2/zed_node/pose_with_covariance",
    "/zed2/zed_node/pose",
    "/tf_static",
)
LCM_CHANNEL = "LCM_High_State"
#: The port of the Unitree SDK's LCM URL (udpm://239.255.76.67:7667): never used during a replay.
SDK_LCM_PORT = 7667


def private_lcm_url_problem(url: str) -> Optional[str]:
    """None if ``url`` cannot reach a live A1 LCM server, else why it could.

    Private means: LCM UDP multicast with ``ttl=0`` (the kernel keeps the packets on this host)
    on a port other than the SDK's 7667 (a ``lcm_server_high`` on this host listens there).
    """
    parts = urlparse(url)
    if parts.scheme != "udpm":
        return "not a udpm:// URL (%s)" % url
    ttl = parse_qs(parts.query).get("ttl", ["0"])[-1]
    if ttl != "0":
        return "ttl=%s lets the packets leave this host (need ttl=0)" % ttl
    port = parts.port or SDK_LCM_PORT
    if port == SDK_LCM_PORT:
        return "port %d is the Unitree SDK's: a lcm_server_high on this host would take the commands" % port
    return None


def record_commands(directory: str, duration: float, lcm_url: str,
                    topics: Sequence[str] = ROS_TOPICS) -> Tuple[List[str], List[str]]:
    """(rosbag record, lcm-logger) command lines of one recording into ``directory``.

    The bag is LZ4-compressed and stops by itself after ``duration`` seconds; lcm-logger records
    only ``LCM_High_State`` and is stopped by the caller when the bag is done.
    """
    bag = ["rosbag", "record", "--lz4", "-q", "--duration=%.3f" % duration, "-O", "%s/%s" % (directory, BAG)]
    logger = ["lcm-logger", "-q", "-f", "-c", LCM_CHANNEL, "-l", lcm_url, "%s/%s" % (directory, LCM_LOG)]
    return bag + list(topics), logger


def play_commands(directory: str, lcm_url: str, topics: Iterable[str]) -> Tuple[List[str], List[str]]:
    """(rosbag play, lcm-logplayer) command lines of one replay of ``directory``.

    rosbag publishes ``/clock`` (the stack runs on the recording's time) and only ``topics``;
    lcm-logplayer plays ``LCM_High_State`` on ``lcm_url`` at the recorded pace.
    """
    play = ["rosbag", "play", "--clock", "-q", "%s/%s" % (directory, BAG), "--topics"] + list(topics)
    player = ["lcm-logplayer", "-e", "^%s$" % LCM_CHANNEL, "-l", lcm_url, "%s/%s" % (directory, LCM_LOG)]
    return play, player


def urdf_links(urdf_xml: str) -> set:
    """Names of the links of a URDF (the frames robot_state_publisher publishes)."""
    return {link.get("name") for link in ET.fromstring(urdf_xml).findall("link") if link.get("name")}


def drivers_static_transforms(transforms: Iterable[Tuple[str, str, object]], robot_frames: Iterable[str],
                              ) -> List[Tuple[str, str, object]]:
    """The recorded static transforms the replay must publish again: the sensor drivers' own.

    ``transforms`` are (parent, child, anything) in recording order. A transform whose child the
    robot model defines (``robot_frames``, e.g. :func:`urdf_links`) is published again by the
    stack's robot_state_publisher on replay and is dropped here (two publishers of a frame would
    be a TF clash); of repeated children the last one wins.
    """
    ours = {f.lstrip("/") for f in robot_frames}
    latest = {}  # type: Dict[str, Tuple[str, str, object]]
    for parent, child, payload in transforms:
        if child.lstrip("/") not in ours:
            latest[child.lstrip("/")] = (parent, child, payload)
    return list(latest.values())


def manifest(duration: float, lcm_url: str, topics: Sequence[str], sizes: Dict[str, int]) -> Dict[str, object]:
    """The contents of ``recording.yaml``."""
    return {"duration": float(duration), "lcm_url": lcm_url, "lcm_channel": LCM_CHANNEL, "ros_topics": list(topics),
            "files": dict(sizes)}


def recording_problems(files: Dict[str, int]) -> List[str]:
    """What keeps a directory with these files (name -> size [B]) from being replayed."""
    out = []
    for name in (BAG, LCM_LOG):
        if name not in files:
            out.append("%s missing" % name)
        elif files[name] == 0:
            out.append("%s is empty" % name)
    return out
