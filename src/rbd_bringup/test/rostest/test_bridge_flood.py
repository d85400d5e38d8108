#!/usr/bin/env python3
"""rostest fault (issue 10): e-stop while the WebSocket bridge is flooded.

The robot walks a trick; several WebSocket clients flood rbd_bridge with everything the
allow-list lets in (gestures, heartbeats) and large garbage frames, as fast as they can. While
the flood runs the e-stop is called (1) over the bridge from another client (``call_service
/rbd_controller/em_stop``) and (2) over ROS. Asserted each time: the service reply latency,
zero velocity at the A1 (LCM HighCmd) and ground truth at rest within the bound, and recovery
(release, the robot walks again) once the flood ends. Reuses the fault catalogue's Monitor.
"""

import json
import os
import signal
import subprocess
import sys
import time

import rospy
from std_msgs.msg import String
from std_srvs.srv import SetBool
from test_faults import Faults, fault_names, one_test_per_fault, wait_for
from websockets.sync.client import connect

from rbd_msgs.msg import PathQueue
from rbd_testkit.ports import wait_for_port
from rbd_testkit.ros import run_rostest

FLOOD_CLIENTS = 3
FLOODER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "flood_bridge.py")
# Bounds (A1 command zero, ground truth at rest, service reply) [s]: over ROS the e-stop tests'
# 0.5 / 1.0 + margin for the flood's CPU load; over the bridge the call first has to get through
# the flooded server (measured 0.75 s on the loaded 2-core VM), so 0.5 s more.
BOUNDS = {"ros": (1.0, 1.5, 1.0), "bridge": (1.5, 2.0, 2.5)}


class BridgeFlood(Faults):
    """The fault catalogue with the flood fault and the operator watchdog's ``finish`` policy.

    ``~fault`` / ``~repeat`` as for Faults (the rounds and the helpers walk, assert_stops and
    record come from there), one test per fault (``one_test_per_fault``, shuffled with
    RBD_TEST_SEED): faults_inputs.test runs the sensor-input faults, the frozen driver link and
    these two on one stack.
    """

    def start_trick(self, gesture, timeout=45.0):
        """Release the e-stop if needed and show ``gesture`` until the robot moves in EXECUTING."""
        m = self.m
        last = [0.0]

        def started():  # (the release and the gesture are sent from the predicate until the robot moves)
            if m.speed() > 0.08 and m.state == "EXECUTING":
                return True
            if m.state == "EMERGENCY_STOP":
                self.em_stop(False)
            if m.state == "WAITING_FOR_GESTURE" and time.monotonic() - last[0] > 0.4:
                m.gesture.publish(String(gesture))
                last[0] = time.monotonic()
            return False

        if not wait_for(started, timeout):
            self.fail("the robot never started %r: state %r" % (gesture, m.state))

    def fault_operator_finish(self, i):
        """operator_policy finish: the trick goes on past the timeout, then the robot waits."""
        m = self.m
        self.assertEqual(rospy.get_param("/rbd_controller/operator_policy"), "finish")
        timeout = float(rospy.get_param("/rbd_controller/operator_timeout"))
        queue = []  # the controller's remaining poses of the current trick (latched), newest last
        sub = rospy.Subscriber("/rbd_controller/path_queue", PathQueue, lambda msg: queue.append(list(msg.names)))
        m.arm_heartbeat()
        wait_for(lambda: queue, 5.0)  # the latched remaining poses (none on a stack that never had a trick)

        def long_trick():  # walking, with at least one whole pose after the current one still to go
            return m.state == "EXECUTING" and m.speed() > 0.08 and bool(queue) and len(queue[-1]) >= 2

        # From its own known state: a trick that goes on past the timeout. After another fault the
        # robot may be anywhere in one: if its last pose is under way (its end could come before
        # the timeout), it is let end first; idle, it is shown "spin" (the shortest trick that moves,
        # two 180 deg turns), as on a fresh stack.
        if not long_trick():
            self.assertTrue(wait_for(lambda: m.state in ("WAITING_FOR_GESTURE", "EMERGENCY_STOP"), 60.0),
                            "the trick of the fault before did not end: %s" % m.state)
            self.start_trick("spin")
        sub.unregister()
        with m.lock:
            n_states = len(m.states)
        m.heartbeat = False
        t0 = time.monotonic()

        def lost():
            with m.lock:
                return [t for t, s in m.states[n_states:] if s == "OPERATOR_LOST"]

        # past the timeout the trick still runs: walking, not OPERATOR_LOST
        self.assertFalse(wait_for(lambda: lost(), timeout + 1.0), "finish policy stopped the trick at once")
        t_check = time.monotonic()
        self.assertTrue(wait_for(lambda: m.speed() > 0.08, 10.0) or lost(), "no motion after the timeout")
        self.assertGreater(m.max_speed("truth", t_check - 0.5, time.monotonic()), 0.08,
                           "the robot did not walk on after the heartbeat timeout")
        self.assertTrue(wait_for(lambda: lost(), 90.0), "never reached OPERATOR_LOST after the trick: %s" % m.state)
        t_lost = lost()[0]
        with m.lock:
            trick_end = [t for t, s in m.states[n_states:] if s == "WAITING_FOR_GESTURE"]
        # at rest, and gestures without an operator start nothing
        for _ in range(6):
            m.gesture.publish(String("walk"))
            time.sleep(0.4)
        _cmd, truth = self.assert_stops(t_lost, 1.0, 1.0, hold=1.5)
        self.assertEqual(m.state, "OPERATOR_LOST")
        # the operator is back: waiting for a gesture, which is taken again
        m.heartbeat = True
        self.assertTrue(wait_for(lambda: m.state == "WAITING_FOR_GESTURE", 10.0), m.state)
        t_back = time.monotonic()
        self.walk()
        end_to_lost = (t_lost - trick_end[0]) if trick_end else None
        self.record(run=i, timeout_s=timeout, walked_after_timeout_s=t_check - t0,
                    lost_after_silence_s=t_lost - t0, trick_end_to_lost_s=end_to_lost,
                    truth_stop_s=truth, recovery_s=time.monotonic() - t_back)

    def flood(self, url):
        """Start the flooding clients, each in its own process; wait until they send."""
        flooders = [subprocess.Popen([sys.executable, FLOODER, url, str(n)], stdout=subprocess.PIPE)
                    for n in range(FLOOD_CLIENTS)]
        return flooders

    def stop_flood(self, flooders):
        """Stop the clients; returns (frames, garbage frames, reconnects) summed over them."""
        for f in flooders:
            f.send_signal(signal.SIGINT)
        counts = []
        for f in flooders:
            out, _ = f.communicate(timeout=20.0)
            lines = out.decode().strip().splitlines()
            try:
                counts.append(json.loads(lines[-1]))
            except (IndexError, ValueError):  # stopped before it could report: counts nothing
                counts.append({"frames": 0, "garbage": 0, "reconnects": 0})
        return tuple(sum(c[k] for c in counts) for k in ("frames", "garbage", "reconnects"))

    def bridge_em_stop(self, ws, engaged, call_id):
        """call_service over the bridge; returns (reply latency [s], reply)."""
        t0 = time.monotonic()
        ws.send(json.dumps({"op": "call_service", "id": call_id, "service": "/rbd_controller/em_stop",
                            "args": {"data": engaged}}))
        while True:
            left = t0 + 10.0 - time.monotonic()
            self.assertGreater(left, 0.0, "no em_stop reply over the bridge within 10 s")
            frame = json.loads(ws.recv(timeout=left))
            if frame.get("op") == "service_response" and frame.get("id") == call_id:
                return time.monotonic() - t0, frame

    def fault_bridge_flood(self, i):
        m = self.m
        m.heartbeat = True  # the operator's own 2 Hz heartbeat keeps going (no OPERATOR_LOST)
        port = int(rospy.get_param("~bridge_port"))
        url = "ws://127.0.0.1:%d" % port
        gestures = []
        rospy.Subscriber("/rbd_gestrec/gesture", String, lambda msg: gestures.append(time.monotonic()), queue_size=100)
        # In random order this fault may run first, before the bridge listens (seen in CI: refused).
        wait_for_port(port, timeout=60.0)
        operator = connect(url, compression=None, max_size=None, open_timeout=30)
        rospy.wait_for_service("/rbd_controller/em_stop", 30.0)
        self.em_stop_proxy = rospy.ServiceProxy("/rbd_controller/em_stop", SetBool, persistent=False)
        try:
            for via in ("bridge", "ros"):
                self.walk()
                flooders = self.flood(url)
                t_flood = time.monotonic()
                n_gestures = len(gestures)
                # flood at full speed while the robot walks (the clients need a moment to start)
                self.assertTrue(wait_for(lambda n=n_gestures: len(gestures) > n + 200, 20.0), "the flood never started")

                def walking():
                    with m.lock:
                        commanded = bool(m.commands) and m.commands[-1][1] > 0.05
                    return commanded and m.speed() > 0.08

                # e-stop a walking robot (not one pausing between two poses of the trick)
                self.assertTrue(wait_for(walking, 20.0, step=0.01), "the robot was not walking during the flood")
                cmd_bound, truth_bound, reply_bound = BOUNDS[via]
                t0 = time.monotonic()
                if via == "bridge":
                    reply_s, reply = self.bridge_em_stop(operator, True, "estop%d" % i)
                    self.assertTrue(reply.get("result"), reply)
                    self.assertTrue(reply["values"]["success"], reply)
                else:
                    res = self.em_stop_proxy(True)
                    reply_s = time.monotonic() - t0
                    self.assertTrue(res.success)
                self.assertLess(reply_s, reply_bound, "em_stop reply took %.2f s" % reply_s)
                cmd, truth = self.assert_stops(t0, cmd_bound, truth_bound, hold=1.0)
                self.assertEqual(m.state, "EMERGENCY_STOP")
                frames, garbage, reconnects = self.stop_flood(flooders)
                flood_s = time.monotonic() - t_flood
                relayed = len([t for t in gestures if t >= t_flood])
                self.assertGreater(frames, 200, "the flood did not flood")
                self.assertGreater(garbage, 0, "no garbage frame sent")
                self.assertGreater(relayed, 50, "the bridge relayed no gestures: not flooded")
                # the flood is over: release; the trick resumes
                t_rel = time.monotonic()
                if via == "bridge":
                    _lat, reply = self.bridge_em_stop(operator, False, "release%d" % i)
                    self.assertTrue(reply["values"]["success"], reply)
                else:
                    self.em_stop(False)
                self.assertTrue(wait_for(lambda: m.speed() > 0.08, 30.0), "no walk after the release")
                self.record(run=i, via=via, reply_s=reply_s, cmd_stop_s=cmd, truth_stop_s=truth,
                            recovery_s=time.monotonic() - t_rel, flood_frames=frames,
                            flood_rate_hz=frames / flood_s, gestures_relayed=relayed,
                            garbage_frames=garbage, reconnects=reconnects, bound_s=cmd_bound)
        finally:
            operator.close()


if __name__ == "__main__":
    rospy.init_node("test_faults")
    # One test per fault, in the order of RBD_TEST_SEED (each starts from its own known state)
    case = one_test_per_fault(BridgeFlood, rospy.get_param("~fault"), int(rospy.get_param("~repeat", 1)))
    run_rostest("rbd_bringup", rospy.get_param("~suite", "faults_" + fault_names()[0]), case)
