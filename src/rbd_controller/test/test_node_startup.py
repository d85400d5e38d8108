"""rbd_controller's start-up on a private master: what a client sees first can be acted on.

An operator's GUI (or the demo's audience) shows the controller's state as soon as it arrives
and offers the e-stop release at once. So when the first /rbd_controller/state message is
delivered, /rbd_controller/em_stop and /rbd_controller/collision must already be registered
with the master; before this was so, a release right after the first state failed with
"service /rbd_controller/em_stop does not exist" (the demo under load, 2026-11-26).
"""

import sys

# A separate process is the state's subscriber (a pytest process may be a ROS node only once).
# On the first state it asks the master for the two services, then prints what it found.
PROBE = r"""
import sys
import rosgraph
import rospy
from std_msgs.msg import String

from rbd_testkit import wait_for

rospy.init_node("startup_probe")
master = rosgraph.Master("/startup_probe")
first = []


def registered(name):
    try:
        master.lookupService(name)
        return "yes"
    except rosgraph.MasterError:
        return "no"


def on_state(msg):
    if not first:
        first.append("first state %s em_stop %s collision %s" % (
            msg.data, registered("/rbd_controller/em_stop"), registered("/rbd_controller/collision")))


rospy.Subscriber("/rbd_controller/state", String, on_state)
print("subscribed", flush=True)
wait_for(lambda: first, 90.0, 0.01, abort=rospy.is_shutdown)
print(first[0] if first else "no state within 90 s", flush=True)
"""


def _lines_of(proc, until):
    """Lines the probe prints, until one starts with ``until`` or it exits (it gives up by itself
    90 s after subscribing; pytest's timeout covers a probe that never gets that far)."""
    lines = []
    while True:
        line = proc.stdout.readline()
        if not line:
            break
        lines.append(line.strip())
        if line.startswith(until):
            break
    return lines


def test_services_are_up_when_the_first_state_arrives(ros_env):
    probe = ros_env.start([sys.executable, "-c", PROBE], name="probe", capture=True)
    lines = _lines_of(probe, "subscribed")
    assert lines and lines[-1] == "subscribed", lines
    controller = ros_env.start(["rosrun", "rbd_controller", "rbd_controller"], name="rbd_controller")
    lines = _lines_of(probe, ("first state", "no state"))
    assert lines, "the probe printed nothing:\n%s" % ros_env.tails()
    assert lines[-1] == "first state EMERGENCY_STOP em_stop yes collision yes", (
        lines,
        ros_env.output(controller)[-3000:],
    )
