"""rbd_controller's localization gate through the node (issue 29), on a private master.

The decision is unit-tested in ``test_tricks.py``; this proves the node wires it: the latched
``/rbd_localization/localized`` (std_msgs/Bool, rbd_localization's name and type) reaches the
core. A probe process is the map correction (the latched flag) and rbd_gestrec (the
get_last_gesture service); it releases the e-stop, shows a gesture while the flag is false (the
controller must take it from the service and stay in WAITING_FOR_GESTURE), then sets the flag
true and shows it again (the controller must start the trick: GENERATING_PATH).
"""

import sys

PROBE = r"""
import time

import rospy
from std_msgs.msg import Bool, String
from std_srvs.srv import SetBool

from rbd_msgs.srv import GetLastGesture, GetLastGestureResponse, SetBodyPose, SetBodyPoseResponse
from rbd_testkit import stays_unchanged, wait_for
from rbd_testkit.ros import RosoutWatcher

rospy.init_node("gate_probe")
rosout = RosoutWatcher()
gestures, states, polls = [], [], []


def on_poll(_req):
    polls.append(time.monotonic())
    return GetLastGestureResponse(command=gestures.pop(0) if gestures else "")


rospy.Service("/rbd_gestrec/get_last_gesture", GetLastGesture, on_poll)
body_poses = []  # the driver's body pose service, so the controller's loop does not wait for it
rospy.Service("/set_body_pose", SetBodyPose, lambda req: body_poses.append(req.pitch) or SetBodyPoseResponse(True, ""))
localized = rospy.Publisher("/rbd_localization/localized", Bool, queue_size=1, latch=True)
localized.publish(Bool(data=False))
rospy.Subscriber("/rbd_controller/state", String, lambda m: states.append(m.data))


def wait(cond, timeout):
    return bool(wait_for(cond, timeout, 0.02, abort=rospy.is_shutdown))


print("ready", flush=True)
if not wait(lambda: localized.get_num_connections() > 0 and states, 60.0):
    print("no controller", states, flush=True)
    raise SystemExit(1)
rosout.wait_connected("/rbd_controller", 30.0)
rospy.wait_for_service("/rbd_controller/em_stop", 30.0)
rospy.ServiceProxy("/rbd_controller/em_stop", SetBool)(data=False)
wait(lambda: states[-1] == "WAITING_FOR_GESTURE", 10.0)
wait(lambda: polls, 10.0)  # the first poll after the release drops what it finds: let it find nothing
n = len(states)
mark = rosout.mark()
gestures.append("spin")
taken = wait(lambda: not gestures, 10.0)
k = len(polls)
# The proof that the gesture reached the gate: the controller logs its refusal and polls again (its
# loop went on past the tick that took it; a taken gesture is GENERATING_PATH within that tick).
refused = "no proof"
try:
    stays_unchanged(lambda: list(states[n:]), lambda: rosout.find("refusing gesture 'spin'", since=mark)
                    and len(polls) > k, hold=0.1, timeout=10.0, what="the controller's states", proof="the refusal")
    refused = "refused"
except AssertionError as err:
    refused = str(err)
print("not localized: consumed %s, %s, states %s, body poses %d"
      % (taken, refused, states[n:] or [states[-1]], len(body_poses)), flush=True)
mark = rosout.mark()
localized.publish(Bool(data=True))
wait(lambda: rosout.find("taking gestures again", since=mark), 10.0)  # the flag reached the core
gestures.append("spin")
wait(lambda: "GENERATING_PATH" in states[n:], 10.0)
print("localized: states %s" % states[n:], flush=True)
"""


def _lines(proc):
    lines = []
    for line in proc.stdout:
        lines.append(line.strip())
    return lines


def test_gesture_refused_while_the_map_correction_says_not_localized(ros_env):
    probe = ros_env.start([sys.executable, "-c", PROBE], name="probe", capture=True)
    assert probe.stdout.readline().strip() == "ready", ros_env.tails()
    controller = ros_env.start(["rosrun", "rbd_controller", "rbd_controller"], name="rbd_controller")
    lines = _lines(probe)
    probe.wait(30.0)
    log = ros_env.output(controller)
    # taken from rbd_gestrec, nothing moved: still waiting, only the attentive body pose of the release sent
    expected = "not localized: consumed True, refused, states ['WAITING_FOR_GESTURE'], body poses 1"
    assert expected in lines, (lines, log[-3000:])
    assert "refusing gesture 'spin': not localized in the map" in log, log[-3000:]
    taken = [line for line in lines if line.startswith("localized: states")]
    assert taken and "GENERATING_PATH" in taken[0], (lines, log[-3000:])
    assert "gesture command 'spin'" in log and "taking gestures again" in log, log[-3000:]
