"""A mount changed in the calibration file moves the simulated OS1; the zone stays with the body.

mount_zone.py's measurements for two mounts files, from conftest.py's one run_all: the shipped
config/mounts.yaml (the OS1 on the robot's back, thesis §3.3.1), measured first on the safety
stack (sim.launch with the same arguments as mount_zone.py's own stack), and the same file with
the OS1 centred on the trunk (the mount the URDF used to hard-code), mount_zone.py on a stack of
its own after the control stack. The truth is the simulator's: the
ground-truth body position, a target placed in the world, the cloud the simulated sensor sees
(decoded with sensor_msgs.point_cloud2), and the zone boundaries found by Fig. 23's bisection on
the collision state, measured from the body frame collision_zone.
"""

import json
import os
import sys

import pytest
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from short_run import result  # noqa: E402

THESIS_TOLERANCE = 0.08  # Fig. 23: the boundary within +-80 mm of the set distance
SAME_BOUNDARY = 0.02  # the two mounts' boundaries agree to this; moving the zone with the sensor shifts them 0.08 m
TARGET_SURFACE = 1.2  # mount_zone.py: target surface this far ahead of the body [m]


@pytest.fixture(scope="module")
def runs(short_run):
    """mount_zone.py's measurements per mounts file, with the file's os_sensor xyz as ``file_xyz``."""
    path = os.path.join(short_run["out"], "mount_check.json")
    assert os.path.exists(path), "mount_zone.py wrote nothing; run_all's output:\n" + short_run["stdout"][-6000:]
    with open(path) as fh:
        results = {"back": result(short_run, "mount"), "centre": json.load(fh)}
    for name, mounts in short_run["mount_files"].items():
        assert results[name]["mounts"] == os.path.abspath(mounts), (name, results[name]["mounts"])
        with open(mounts) as fh:
            results[name]["file_xyz"] = yaml.safe_load(fh)["os_sensor"]["xyz"]
    return results


def test_the_sensor_frames_and_the_simulated_sensor_move_with_the_file(runs):
    assert runs["back"]["file_xyz"][0] < -0.05  # the shipped mount is on the rear half of the back
    for r in runs.values():
        assert r["tf_mount"] == pytest.approx(r["file_xyz"], abs=1e-6)
        # Where the simulated OS1 really is: the target's returns sit at (surface - body - mount) in os_sensor.
        assert r["cloud_x"] == pytest.approx(TARGET_SURFACE - r["file_xyz"][0], abs=0.015), r
    assert runs["back"]["cloud_x"] - runs["centre"]["cloud_x"] == pytest.approx(0.08, abs=0.015)


@pytest.mark.parametrize("side", ["front", "back"])
def test_the_zone_keeps_its_boundaries_relative_to_the_body(runs, side):
    for r in runs.values():
        assert r[side] is not None, r
        assert abs(r[side] - r[side + "_set"]) <= THESIS_TOLERANCE, r
    assert runs["back"][side] == pytest.approx(runs["centre"][side], abs=SAME_BOUNDARY)
