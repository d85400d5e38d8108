"""The robot link: the only package of rbd_local that imports roslibpy.

:class:`RobotLink` (:mod:`.robot_link`) is the laptop app's one connection to the robot's
``rbd_bridge``: the reconnecting link thread, with the keep-alive (:mod:`.keepalive`), one
roslibpy client per connection (:mod:`.connection`) and the blocking service calls
(:mod:`.service_calls`). The ROS names and the message helpers live outside the package
(:mod:`rbd_local.robot_names`, :mod:`rbd_local.robot_messages`) so the GUI can use them without
the link; they are re-exported here for the link's callers.
"""

from rbd_local.link.keepalive import KEEPALIVE_PINGS  # noqa: F401
from rbd_local.link.robot_link import RobotLink  # noqa: F401
from rbd_local.robot_messages import preflight_report_from_msg, tricks_from_param  # noqa: F401
from rbd_local.robot_names import (  # noqa: F401
    CAMERA_TOPIC,
    CAMERA_TYPE,
    EM_STOP_SERVICE,
    GESTURE_TOPIC,
    HEARTBEAT_TOPIC,
    PATH_QUEUE_TOPIC,
    PREFLIGHT_MAX_DURATION_S,
    PREFLIGHT_SERVICE,
    PREFLIGHT_SERVICE_TYPE,
    PREFLIGHT_STATUSES,
    PREFLIGHT_TOPIC,
    PREFLIGHT_TYPE,
    STATE_TOPIC,
    STATUS_COLLISION,
    STATUS_EMERGENCY,
    STATUS_IDLE,
    STATUS_RUNNING,
    STATUS_TOPIC,
    TRICKS_PARAM,
)
