"""The robot's own status light: the operator GUI's state colour in ``HighCmd.led`` (ROS-free).

The operator GUI (``rbd_local.gui.app.STATUS_COLOURS``) colours its state label by the position
controller's status: emergency red, collision orange, idle blue, running green, anything else
grey. The driver mirrors the same colour into the four ``LED`` (r, g, b) entries of every
HighCmd, so people around the robot see its state on the robot itself (thesis §5.3). Whether the
A1 firmware shows ``led`` in high-level mode is unverified. The driver's own e-stop (remote,
controller flag, lost signal) shows red whatever the status says: that is what the GUI will show.
"""

from typing import Tuple

from rbd_msgs.msg import PosControllerStatus as Status

RGB = Tuple[int, int, int]

#: Status (``/rbd_pos_controller/status``) -> colour, the GUI's hex colours as bytes.
STATUS_RGB = {
    Status.EMERGENCY: (0xC6, 0x28, 0x28),  # red     #c62828
    Status.COLLISION: (0xEF, 0x6C, 0x00),  # orange  #ef6c00
    Status.IDLE: (0x15, 0x65, 0xC0),  # blue    #1565c0
    Status.RUNNING: (0x2E, 0x7D, 0x32),  # green   #2e7d32
}
UNKNOWN_RGB = (0x61, 0x61, 0x61)  # grey #616161: no status yet / unknown
LED_COUNT = 4


def led_colour(status: str, estopped: bool) -> RGB:
    """Colour for the robot's LEDs.

    Args:
        status: the last ``/rbd_pos_controller/status`` ("" if none yet).
        estopped: the driver's gate is held by an e-stop.

    Returns:
        (r, g, b), 0..255.
    """
    if estopped:
        return STATUS_RGB[Status.EMERGENCY]
    return STATUS_RGB.get(status, UNKNOWN_RGB)


def led_bytes(rgb: RGB) -> bytes:
    """The 12 bytes of ``HighCmd.led[4]``: the same (r, g, b) on every LED."""
    return bytes(bytearray(rgb)) * LED_COUNT
