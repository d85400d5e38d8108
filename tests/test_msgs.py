"""rbd_msgs is generated and importable with the fields the other packages rely on."""

import subprocess


def test_generate_path_fields():
    from rbd_msgs.srv import GeneratePathRequest, GeneratePathResponse

    assert GeneratePathRequest.__slots__ == ["command"]
    assert GeneratePathResponse.__slots__ == ["success", "message", "poses", "count", "names"]


def test_collision_state_constants_and_sizes():
    from rbd_msgs.msg import CollisionState

    msg = CollisionState()
    assert (CollisionState.FRONT, CollisionState.LEFT, CollisionState.BACK, CollisionState.RIGHT) == (0, 1, 2, 3)
    assert len(msg.points) == 4 and len(msg.min_distance) == 4


def test_set_body_pose_matches_qre_fields():
    from rbd_msgs.srv import SetBodyPoseRequest

    assert SetBodyPoseRequest.__slots__ == ["roll", "pitch", "yaw", "body_height"]


def test_rossrv_show_prints_fields():
    out = subprocess.run(["rossrv", "show", "rbd_msgs/GeneratePath"], stdout=subprocess.PIPE, check=True,
                         universal_newlines=True).stdout
    assert "string command" in out and "geometry_msgs/Pose[] poses" in out and "string[] names" in out


def test_rospack_lists_every_package():
    out = subprocess.run(["rospack", "list-names"], stdout=subprocess.PIPE, check=True, universal_newlines=True).stdout
    names = set(out.split())
    # rospack skips metapackages (robodog); every rbd package must be there.
    expected = {"rbd_msgs", "rbd_lidar", "rbd_controller", "rbd_pos_controller", "rbd_localization",
                "rbd_navigation", "rbd_gestrec", "rbd_bridge", "rbd_a1_driver", "rbd_sim", "rbd_bringup",
                "rbd_description", "rbd_preflight", "rbd_testkit"}
    assert expected <= names, expected - names


def test_preflight_check_status_constants_are_the_status_words():
    """The constants are what a consumer compares ``status`` with (ROS 1 string constants take the rest of the line).

    The values come from the generated class, as rospy users see them; the words are rbd_preflight's.
    """
    import rbd_preflight as preflight
    from rbd_msgs.msg import PreflightCheck

    got = (PreflightCheck.PASS, PreflightCheck.FAIL, PreflightCheck.SKIP)
    assert got == (preflight.PASS, preflight.FAIL, preflight.SKIP)
