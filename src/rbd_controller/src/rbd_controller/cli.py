"""Argument handling of `rosrun rbd_controller estop on|off`. Runs without ROS too."""

from typing import List, Optional, Sequence

try:
    from rospy import myargv
except ImportError:  # no ROS here (a laptop's unit tests): a ROS argument is one with ":="

    def myargv(argv: Sequence[str]) -> List[str]:
        """The arguments without ROS remappings (``a:=b``, ``__name:=x``, ``_param:=1``)."""
        return [a for a in argv if ":=" not in a]

ON_WORDS = ("on", "engage", "true", "1", "stop")
OFF_WORDS = ("off", "release", "false", "0", "go")


def parse_estop_args(argv: Sequence[str]) -> Optional[bool]:
    """Return True to engage, False to release, None if argv is not one valid word."""
    args = myargv(list(argv))  # without ROS remappings: __name:=x, a:=b, _param:=1
    if len(args) != 1:
        return None
    word = args[0].strip().lower()
    if word in ON_WORDS:
        return True
    if word in OFF_WORDS:
        return False
    return None
