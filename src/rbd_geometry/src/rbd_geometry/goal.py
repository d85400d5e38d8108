"""A goal pose of the robot: where it walks to and the body attitude it holds there. ROS-free.

The one model of a goal shared by the position controller (rbd_pos_controller: the goal it walks
to) and the navigation (rbd_navigation: a trick's steps expanded around the robot, each named for
the GUI's list of the next moves).
"""


class Goal:
    """A goal pose: position [m], heading [rad], body roll/pitch [rad], body height change [m].

    Args:
        x: position x in the goal's frame [m].
        y: position y [m].
        yaw: heading [rad].
        roll: body roll to hold at the goal [rad] (0: level).
        pitch: body pitch to hold at the goal [rad].
        body_height: body height change at the goal [m] (0: neutral).
        name: what the goal is for, for people (a trick step's name; empty: unnamed).
    """

    __slots__ = ("x", "y", "yaw", "roll", "pitch", "body_height", "name")

    def __init__(
        self,
        x: float,
        y: float,
        yaw: float,
        roll: float = 0.0,
        pitch: float = 0.0,
        body_height: float = 0.0,
        name: str = "",
    ) -> None:
        self.x = x
        self.y = y
        self.yaw = yaw
        self.roll = roll
        self.pitch = pitch
        self.body_height = body_height
        self.name = name

    def __repr__(self) -> str:
        """Readable form for logs and test failures."""
        return "Goal(%sx=%.3f, y=%.3f, yaw=%.3f, roll=%.3f, pitch=%.3f, body_height=%.3f)" % (
            "%r, " % self.name if self.name else "",
            self.x,
            self.y,
            self.yaw,
            self.roll,
            self.pitch,
            self.body_height,
        )
