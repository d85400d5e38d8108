#!/usr/bin/env python3
"""ROS side for the live-bridge test: a stand-in controller that reports what reaches ROS.

Serves /rbd_controller/em_stop, listens to /rbd_gestrec/gesture and /rbd_local/heartbeat,
publishes latched /rbd_pos_controller/status, /rbd_controller/state and /rbd_controller/path_queue.
Prints one line per event on stdout.
"""

import sys

import rospy
from rbd_msgs.msg import PathQueue
from rbd_msgs.msg import PosControllerStatus as Status
from std_msgs.msg import Header, String
from std_srvs.srv import SetBool, SetBoolResponse


def main():
    rospy.init_node("rbd_local_test_peer", anonymous=True)

    def say(text):
        sys.stdout.write(text + "\n")
        sys.stdout.flush()

    def em_stop(req):
        say("EMSTOP %s" % req.data)
        status.publish(String(data=Status.EMERGENCY if req.data else Status.IDLE))
        return SetBoolResponse(success=True, message="engaged" if req.data else "released")

    status = rospy.Publisher("/rbd_pos_controller/status", String, queue_size=1, latch=True)
    state = rospy.Publisher("/rbd_controller/state", String, queue_size=1, latch=True)
    queue = rospy.Publisher("/rbd_controller/path_queue", PathQueue, queue_size=1, latch=True)
    rospy.Subscriber("/rbd_gestrec/gesture", String, lambda m: say("GESTURE %s" % m.data))
    rospy.Subscriber("/rbd_local/heartbeat", Header, lambda m: say("HEARTBEAT %d" % m.seq))
    rospy.Service("/rbd_controller/em_stop", SetBool, em_stop)
    status.publish(String(data=Status.IDLE))
    state.publish(String(data="WAITING_FOR_GESTURE"))
    queue.publish(PathQueue(command="walk", names=["walk: to (0.6, 0)", "walk: back"]))
    say("READY")
    rospy.spin()


if __name__ == "__main__":
    main()
