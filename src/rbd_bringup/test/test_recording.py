"""rbd_bringup.recording (ROS-free): the private-URL rule, the command lines, the drivers' static frames.

lcm-logplayer's command line is checked against the tool's own option parser where liblcm-bin is
installed (the recording and the replay themselves run in test_replay.py).
"""

import shutil
import subprocess

import pytest

from rbd_bringup import recording

URDF = """<robot name="a1"><link name="base_link"/><link name="os_sensor"/><link name="zed2_camera_center"/>
<joint name="j" type="fixed"><parent link="base_link"/><child link="os_sensor"/></joint></robot>"""


@pytest.mark.parametrize("url, problem", [
    ("udpm://239.255.76.67:7667?ttl=0", "port 7667"),  # the Unitree SDK's URL
    ("udpm://239.255.76.67?ttl=0", "port 7667"),  # LCM's default port is the SDK's
    ("udpm://239.255.76.67:23000?ttl=1", "ttl=1"),
    ("udpm://239.255.76.67:23000", None),  # LCM's default ttl is 0
    ("udpm://239.255.76.67:23000?ttl=0", None),
    ("tcpq://127.0.0.1:7700", "not a udpm"),
])
def test_private_lcm_url(url, problem):
    found = recording.private_lcm_url_problem(url)
    if problem is None:
        assert found is None
    else:
        assert problem in found


def test_record_and_play_commands():
    bag, logger = recording.record_commands("/r", 8.0, "udpm://239.255.76.67:7667?ttl=0")
    assert bag[:2] == ["rosbag", "record"] and "--lz4" in bag and "--duration=8.000" in bag
    assert bag[bag.index("-O") + 1] == "/r/sensors.bag"
    assert bag[-len(recording.ROS_TOPICS):] == list(recording.ROS_TOPICS)
    assert logger[0] == "lcm-logger" and logger[logger.index("-c") + 1] == "LCM_High_State"
    assert logger[-1] == "/r/a1_highstate.lcmlog" and logger[logger.index("-l") + 1].endswith("7667?ttl=0")
    play, player = recording.play_commands("/r", "udpm://239.255.76.67:23000?ttl=0", ["/ouster/points"])
    assert play[:3] == ["rosbag", "play", "--clock"] and play[-2:] == ["--topics", "/ouster/points"]
    assert player[0] == "lcm-logplayer" and player[player.index("-l") + 1] == "udpm://239.255.76.67:23000?ttl=0"
    assert player[-1] == "/r/a1_highstate.lcmlog"


@pytest.mark.skipif(not shutil.which("lcm-logplayer"), reason="liblcm-bin not installed")
def test_lcm_tools_accept_the_options(tmp_path):
    # lcm-logplayer on a missing file: it parsed the options and stopped at the file
    _play, player = recording.play_commands(str(tmp_path), "udpm://239.255.76.67:23000?ttl=0", [])
    out = subprocess.run(player, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=10)
    assert out.returncode != 0 and "unrecognized option" not in out.stdout and "invalid option" not in out.stdout


def test_only_the_drivers_static_frames_are_replayed():
    links = recording.urdf_links(URDF)
    assert links == {"base_link", "os_sensor", "zed2_camera_center"}
    recorded = [("base_link", "os_sensor", 1), ("os_sensor", "os_imu", 2), ("os_sensor", "os_lidar", 3),
                ("base_link", "zed2_camera_center", 4), ("os_sensor", "os_imu", 5)]
    again = recording.drivers_static_transforms(recorded, links)
    assert sorted(again) == [("os_sensor", "os_imu", 5), ("os_sensor", "os_lidar", 3)]


def test_recording_problems_and_manifest():
    assert recording.recording_problems({"sensors.bag": 10, "a1_highstate.lcmlog": 5}) == []
    assert recording.recording_problems({"sensors.bag": 10}) == ["a1_highstate.lcmlog missing"]
    assert recording.recording_problems({"sensors.bag": 0, "a1_highstate.lcmlog": 5}) == ["sensors.bag is empty"]
    m = recording.manifest(8.0, "udpm://x", recording.ROS_TOPICS, {"sensors.bag": 10})
    assert m["lcm_channel"] == "LCM_High_State" and m["files"] == {"sensors.bag": 10}
