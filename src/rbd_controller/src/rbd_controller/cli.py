"""Argument handling of `rosrun rbd_controller estop on|off`. ROS-free."""

from typing import Optional, Sequence

ON_WORDS = ("on", "engage", "true", "1", "stop")
OFF_WORDS = ("off", "release", "false", "0", "go")


def parse_estop_args(argv: Sequence[str]) -> Optional[bool]:
    """Return True to engage, False to release, None if argv is not one valid word."""
    args = [a for a in argv if not a.startswith("__")]  # drop ROS remapping args like __name:=
    if len(args) != 1:
        return None
    word = args[0].strip().lower()
    if word in ON_WORDS:
        return True
    if word in OFF_WORDS:
        return False
    return None
