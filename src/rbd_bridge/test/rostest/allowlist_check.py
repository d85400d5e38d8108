#!/usr/bin/env python3
"""rostest node: the RoboDog bridge denies /cmd_vel and passes gestures into ROS."""

import json
import threading
import time
import unittest

import rosgraph
import rospy
from std_msgs.msg import String
from websockets.sync.client import connect

from rbd_testkit import wait_for
from rbd_testkit.ros import run_rostest


class AllowListWiring(unittest.TestCase):
    def setUp(self):
        rospy.init_node("allowlist_check", anonymous=True)
        self.port = wait_for(lambda: rospy.get_param("/rbd_bridge/actual_port", None), 30.0, 0.1)
        self.assertIsNotNone(self.port, "the bridge never published ~actual_port")

    def test_cmd_vel_denied_and_gesture_forwarded(self):
        got = []
        event = threading.Event()

        def on_gesture(msg):
            got.append(msg.data)
            event.set()

        rospy.Subscriber("/rbd_gestrec/gesture", String, on_gesture)
        ws = connect("ws://127.0.0.1:%d" % self.port, compression=None, open_timeout=15)
        try:
            ws.send(json.dumps({"op": "set_level", "level": "error"}))
            ws.send(json.dumps({"op": "advertise", "id": "a", "topic": "/cmd_vel", "type": "geometry_msgs/Twist"}))
            status = json.loads(ws.recv(timeout=10))
            self.assertEqual(status["op"], "status")
            self.assertIn("allow-list", status["msg"])
            ws.send(json.dumps({"op": "advertise", "topic": "/rbd_gestrec/gesture", "type": "std_msgs/String"}))
            deadline = time.monotonic() + 20
            while not event.is_set() and time.monotonic() < deadline:
                ws.send(json.dumps({"op": "publish", "topic": "/rbd_gestrec/gesture", "msg": {"data": "wave"}}))
                event.wait(0.2)
        finally:
            ws.close()
        self.assertEqual(got[0], "wave")
        publishers = dict(rosgraph.Master("/allowlist_check").getSystemState()[0])
        self.assertNotIn("/cmd_vel", publishers)

    def test_tricks_parameter_readable_not_writable(self):
        """rbd_bridge.launch gives a params_glob: readable, yet read-only (rosbridge would allow writes)."""
        rospy.set_param("/rbd_navigation/tricks", ["sit"])
        ws = connect("ws://127.0.0.1:%d" % self.port, compression=None, open_timeout=15)
        try:
            for i, (service, args) in enumerate(
                [
                    ("/rosapi/get_param", {"name": "/rbd_navigation/tricks"}),
                    ("/rosapi/set_param", {"name": "/rbd_navigation/tricks", "value": '["jump"]'}),
                    ("/rosapi/delete_param", {"name": "/rbd_navigation/tricks"}),
                    ("/rosapi/get_param", {"name": "/rbd_navigation/tricks"}),
                ]
            ):
                ws.send(json.dumps({"op": "call_service", "id": "c%d" % i, "service": service, "args": args}))
            replies = {}
            while len(replies) < 4:
                frame = json.loads(ws.recv(timeout=10))
                replies[frame["id"]] = frame
        finally:
            ws.close()
        self.assertTrue(replies["c0"]["result"])
        self.assertEqual(json.loads(replies["c0"]["values"]["value"]), ["sit"])
        self.assertFalse(replies["c1"]["result"])  # refused: the writes were answered, and failed
        self.assertFalse(replies["c2"]["result"])
        self.assertEqual(json.loads(replies["c3"]["values"]["value"]), ["sit"])
        self.assertEqual(rospy.get_param("/rbd_navigation/tricks"), ["sit"])  # the master's truth


if __name__ == "__main__":
    run_rostest("rbd_bridge", "bridge_allowlist", AllowListWiring)
