"""Node wiring that is quickest to check with a private master: bad worlds stop the nodes at startup."""

import subprocess

import pytest


def run_node(ros_env, node, world, timeout=40):
    return ros_env.run_to_exit(["rosrun", "rbd_sim", node, "_world:=%s" % world], timeout=timeout)


@pytest.mark.parametrize("node", ["world", "os1_sim"])
def test_unknown_world_entry_is_a_clear_startup_error(ros_env, tmp_path, node):
    bad = tmp_path / "bad.yaml"
    bad.write_text("walls:\n  - {from: [0, 0], to: [1, 0], heigth: 2.0}\n")
    code, log = run_node(ros_env, node, str(bad))
    assert code == 1, log
    assert "unknown key(s) ['heigth']" in log and "walls[0]" in log, log


def test_missing_world_lists_known_worlds(ros_env):
    code, log = run_node(ros_env, "world", "atlantis")
    assert code == 1
    assert "known worlds" in log and "lab" in log and "fair" in log, log


def test_rosrun_available():
    assert subprocess.call(["which", "rosrun"], stdout=subprocess.DEVNULL) == 0


def test_bad_mount_in_the_calibration_file_is_a_clear_startup_error(ros_env):
    code, log = ros_env.run_to_exit(["rosrun", "rbd_sim", "os1_sim", "_world:=lab",
                                     "_mounts:={os_sensor: {parent: base_link, xyz: [0, 0], rpy: [0, 0, 0]}}"],
                                    timeout=40)
    assert code == 1, log
    assert "mount os_sensor.xyz must be 3 numbers" in log, log


def test_bad_late_cloud_parameter_is_a_clear_startup_error(ros_env):
    code, log = ros_env.run_to_exit(["rosrun", "rbd_sim", "os1_sim", "_world:=lab", "_cloud_delay:=0.15",
                                     "_late_fraction:=1.5", "_late_delay:=0.3"], timeout=40)
    assert code == 1, log
    assert "late_fraction must be in [0, 1]" in log, log
