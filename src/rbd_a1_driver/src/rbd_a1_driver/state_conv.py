"""HighState -> plain odometry/IMU values (ROS-free; the node copies them into messages)."""

from rbd_a1_driver import unitree_layout as ul


class OdomValues:
    """Odometry of base_link in the robot's power-up frame, from one HighState."""

    __slots__ = ("position", "orientation", "linear", "angular", "body_height")

    def __init__(self, position: tuple, orientation: tuple, linear: tuple, angular: tuple,
                 body_height: float) -> None:
        self.position = position  # x, y, z [m] (z = 0: the odom frame is planar)
        self.orientation = orientation  # x, y, z, w (ROS order)
        self.linear = linear  # body frame [m/s]
        self.angular = angular  # body frame [rad/s]
        self.body_height = body_height  # absolute [m]


def odom_from_state(state: ul.HighState) -> OdomValues:
    """Convert the A1's own odometry + IMU into odometry values.

    Position is the SDK's ``position`` (leg odometry, drifts); orientation is the IMU quaternion,
    reordered from the SDK's (w, x, y, z) to ROS (x, y, z, w); linear velocity is ``velocity``
    (body frame), angular velocity the gyroscope.
    """
    w, x, y, z = state.quaternion
    return OdomValues(
        (state.position[0], state.position[1], 0.0),
        (x, y, z, w),
        (state.velocity[0], state.velocity[1], state.velocity[2]),
        tuple(state.gyroscope),
        state.body_height,
    )
