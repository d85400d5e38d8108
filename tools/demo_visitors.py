"""The demo's visitors and operator: a person in the way, a bag on the path, the operator's moves.

A person steps into the robot's way, a bag is put down on its path, and the operator walks the
waiting robot to a pose (`make demo`).

Each acts on the simulated world through rbd_sim's services (or the position controller) and
judges what happened on the demo's monitor (tools/demo_monitor.py). Used by tools/demo_scenario.py.
"""

import math
import threading
import time

from demo_monitor import say

from rbd_geometry.rotation import yaw_to_quat
from rbd_testkit import wait_for


def drop_bag(monitor):
    """A bag is put down 0.5 m ahead of the robot's footprint on its way out; it stays until the trick is done.

    Dropped right after the start (0.05 m along), so that the bag (0.5 m deep along the path when
    turned 0.3 rad) ends 1.3 m along, out of the stop zone of the stroll's far pose (2 m along, the
    zone reaching 0.63 m behind it): the robot gets around it and reaches that pose.
    """
    import rospy

    from rbd_bringup.metrics import box_ahead
    from rbd_msgs.srv import PlaceBox

    place = rospy.ServiceProxy("/rbd_sim/place_box", PlaceBox)
    start = monitor.pose

    def walking_out():
        x, y, _ = monitor.pose
        along = (x - start[0]) * math.cos(start[2]) + (y - start[1]) * math.sin(start[2])
        with monitor.lock:
            moving = monitor.commands and monitor.commands[-1][1] > 0.1
        return moving and monitor.state == "EXECUTING" and along > 0.05

    wait_for(walking_out, 20.0)
    x, y, yaw = monitor.pose
    # 0.5 m ahead of the footprint: outside the stop zone (0.37 m ahead of it), not dropped onto the robot.
    bx, by, byaw = box_ahead((x, y, yaw), 0.5, (0.4, 0.4), box_yaw=0.3)
    say("a visitor puts a bag (0.4 m box) down 0.5 m ahead of the walking robot at (%.2f, %.2f)" % (bx, by))
    place(name="bag", x=bx, y=by, yaw=byaw, size_x=0.4, size_y=0.4, height=0.4, remove=False)

    def take_away():
        monitor.wait_state(("WAITING_FOR_GESTURE",), 120.0)
        place(name="bag", remove=True)
        say("the bag is taken away")

    threading.Thread(target=take_away, daemon=True).start()


def turn(monitor, yaw, xy=None):
    """The operator walks the waiting robot to ``xy`` (default: where it stands) to face ``yaw`` (world).

    With the position controller, as an operator does with a joystick (not through the bridge).
    """
    import rospy
    from geometry_msgs.msg import Pose

    from rbd_msgs.srv import SetPosition

    monitor.wait_state(("WAITING_FOR_GESTURE",), 30.0)
    x, y = xy if xy is not None else monitor.pose[:2]
    goal = Pose()
    goal.position.x, goal.position.y = x, y
    _x, _y, goal.orientation.z, goal.orientation.w = yaw_to_quat(yaw)
    rospy.wait_for_service("/rbd_pos_controller/set_position", 10.0)
    rospy.ServiceProxy("/rbd_pos_controller/set_position", SetPosition)(pose=goal)
    turned = wait_for(lambda: abs(math.sin((monitor.pose[2] - yaw) / 2.0)) < 0.03
                      and math.hypot(monitor.pose[0] - x, monitor.pose[1] - y) < 0.05, 30.0)
    say("the operator walks the robot to (%.2f, %.2f) facing %.0f deg: %s"
        % (x, y, math.degrees(yaw), "done" if turned else "not done"))


def intrude(monitor, n_log):
    """A visitor steps into the robot's way while it walks, waits, and leaves.

    Runs beside the audience's show: it waits for the trick to start after the monitor's
    ``n_log``-th logged state change (the app may send the command long before its clip ends).
    """
    import rospy

    from rbd_msgs.srv import PlaceObstacle

    place = rospy.ServiceProxy("/rbd_sim/place_obstacle", PlaceObstacle)

    def start_pose():
        with monitor.lock:
            return next((pose for (_, state), pose in zip(monitor.state_log[n_log:], monitor.state_poses[n_log:])
                         if state in ("GENERATING_PATH", "EXECUTING") and pose is not None), None)

    if not wait_for(lambda: start_pose() is not None, 150.0):
        say("the visitor waited for the trick in vain")
        return
    # The person stands 1.0 m ahead of where the walk started (the robot's ground truth when the
    # controller took the trick), on its first leg (0.6 m forward), and steps in once the robot
    # walks. Placed relative to the robot's pose at the step-in instead, a late step-in (a loaded
    # machine: 1.9 s after the walk began, in one CI run) put the person beyond the end of the leg,
    # and the robot turned back before its zone reached them.
    x, y, yaw = start_pose()

    def walking():
        with monitor.lock:
            moving = monitor.commands and monitor.commands[-1][1] > 0.1
        return moving and monitor.state == "EXECUTING"

    wait_for(walking, 15.0)
    px, py = x + 1.0 * math.cos(yaw), y + 1.0 * math.sin(yaw)
    say("a visitor steps in 1.0 m ahead of the walk's start, at (%.2f, %.2f), while the robot walks" % (px, py))
    place("visitor", px, py, 0.2, 1.7, False)
    stopped = monitor.wait_state(("COLLISION_DETECTED",), 10.0)
    say("robot %s" % ("stopped for the visitor" if stopped else "did NOT stop"))
    # A short wait: half rbd_controller's blocked_timeout (3 s), after which a still person counts as
    # blocking and the robot starts to avoid (staying 3.0 s raced it: BLOCKED at 3.5 s, one CI run
    # then went round instead of resuming).
    time.sleep(1.5)
    place("visitor", px, py, 0.2, 1.7, True)
    say("the visitor leaves")
