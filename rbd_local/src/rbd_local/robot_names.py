"""The robot's ROS names the laptop app uses: topics, services, parameters, types and status words.

Plain constants (no roslibpy): the GUI imports them without pulling in the link. The status
words are the ones ``rbd_msgs/PosControllerStatus`` names on the robot side
(``tests/test_robot_names.py`` compares the two).
"""

GESTURE_TOPIC = "/rbd_gestrec/gesture"
HEARTBEAT_TOPIC = "/rbd_local/heartbeat"
EM_STOP_SERVICE = "/rbd_controller/em_stop"
STATUS_TOPIC = "/rbd_pos_controller/status"
STATE_TOPIC = "/rbd_controller/state"
PATH_QUEUE_TOPIC = "/rbd_controller/path_queue"
#: The ZED2 wrapper's left image through image_transport's compressed plugin.
CAMERA_TOPIC = "/zed2/zed_node/left/image_rect_color/compressed"
CAMERA_TYPE = "sensor_msgs/CompressedImage"
#: rbd_navigation's tricks (its private parameter, loaded from config/tricks.yaml).
TRICKS_PARAM = "/rbd_navigation/tricks"
#: rbd_preflight's preflight_server (node ``/preflight``): runs the checks on demand (read-only).
PREFLIGHT_SERVICE = "/preflight/run"
PREFLIGHT_SERVICE_TYPE = "rbd_msgs/RunPreflight"
#: The last report, latched.
PREFLIGHT_TOPIC = "/preflight/report"
PREFLIGHT_TYPE = "rbd_msgs/PreflightReport"
PREFLIGHT_STATUSES = ("PASS", "FAIL", "SKIP")
PREFLIGHT_MAX_DURATION_S = 10.0

#: The words of ``/rbd_pos_controller/status`` (std_msgs/String), as rbd_msgs/PosControllerStatus names them.
STATUS_IDLE = "idle"
STATUS_RUNNING = "running"
STATUS_EMERGENCY = "emergency"
STATUS_COLLISION = "collision"
