"""conversions.yaw_of: the heading the node hands to perception; a malformed quaternion is no pose."""

import math
from types import SimpleNamespace

import pytest

from rbd_controller.conversions import yaw_of
from rbd_controller.perception import AvoidParams, Perception


def _q(x, y, z, w):
    return SimpleNamespace(x=x, y=y, z=z, w=w)


def test_heading_of_a_turn_about_z():
    # 120 deg about z, written from the half angle by hand
    assert yaw_of(_q(0.0, 0.0, math.sin(math.radians(60)), math.cos(math.radians(60)))) == pytest.approx(
        math.radians(120))


@pytest.mark.parametrize("bad", [_q(0.0, 0.0, 0.0, 0.0), _q(0.0, 0.0, float("nan"), 1.0), _q(float("inf"), 0, 0, 1)])
def test_a_zero_or_non_finite_quaternion_is_nan_and_perception_keeps_no_pose(bad):
    assert math.isnan(yaw_of(bad))  # heading 0 would place the robot's obstacles wrongly
    perception = Perception(AvoidParams())
    perception.on_pose(1.0, 0.5, 0.5, yaw_of(bad))
    assert perception.pose is None


def _cloud(rows, names=("x", "y", "z", "intensity")):
    """A PointCloud2-like object (FLOAT32 fields, pcl::PointXYZI's 32-byte step) holding rows."""
    import numpy as np

    step = 32
    data = bytearray(step * len(rows))
    for i, row in enumerate(rows):
        data[i * step: i * step + 4 * len(row)] = np.asarray(row, dtype="<f4").tobytes()
    fields = [SimpleNamespace(name=n, offset=4 * k, datatype=7, count=1) for k, n in enumerate(names)]
    return SimpleNamespace(fields=fields, is_bigendian=False, width=len(rows), height=1, point_step=step,
                           row_step=step * len(rows), data=bytes(data))


def test_collision_points_with_z_say_whether_they_are_a_low_obstacle():
    from rbd_controller.conversions import blocking_points, cloud_xyz

    top = math.radians(20.5477)
    bag = [(0.8, y, z, 1.0) for y in (-0.1, 0.0, 0.1) for z in (-0.2, 0.0, 0.04)]  # its top 0.04 m above the sensor
    person = bag + [(0.8, 0.0, 0.29, 1.0)]  # ... and a point at the top beam (0.30 m up at 0.8 m)
    assert cloud_xyz(_cloud(bag)).shape == (9, 3)
    xy, low = blocking_points(_cloud(bag), top)
    assert low and xy.shape == (9, 2) and xy[0].tolist() == pytest.approx([0.8, -0.1])
    assert not blocking_points(_cloud(person), top)[1]
    assert not blocking_points(_cloud(bag), None)[1]  # no beam table: no low rule
    no_z = _cloud([(0.8, 0.0)], names=("x", "y"))
    xy, low = blocking_points(no_z, top)
    assert xy.shape == (1, 2) and not low
    with pytest.raises(ValueError):
        cloud_xyz(no_z)
