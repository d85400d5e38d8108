"""The demo's monitor: what `make demo` measures while the scripted show runs, and its progress log.

Ground truth (the path, contacts with people and boxes), the people and boxes of the simulated
world, the main controller's states, the LiDAR zone's stop onsets and the stream of HighCmds the
A1 receives over LCM. Used by tools/demo_scenario.py and tests/experiments (reaction times).
"""

import math
import threading
import time

from rbd_geometry.rotation import yaw_of
from rbd_testkit import wait_for

T0 = time.monotonic()


def say(msg):
    """Print one progress line with the time since the demo started."""
    print("[demo %6.1f s] %s" % (time.monotonic() - T0, msg), flush=True)


T0 = time.monotonic()


class Monitor:
    """Ground truth, people, controller states, LiDAR onsets and the A1's LCM command stream."""

    def __init__(self, lcm_url):
        import rospy
        from nav_msgs.msg import Odometry
        from std_msgs.msg import String
        from visualization_msgs.msg import MarkerArray

        from rbd_bringup.a1_monitor import HighCmdMonitor
        from rbd_bringup.demo_report import StopOnsets
        from rbd_bringup.metrics import ContactMonitor, footprint_box_clearance
        from rbd_msgs.msg import CollisionState

        self.lock = threading.Lock()
        self.contacts = ContactMonitor()
        self._box_clearance = footprint_box_clearance
        self.pose = None
        self.path = []
        self.people = {}
        self.people_log = {}
        self.state = ""
        self.state_log = []
        self.state_poses = []  # the ground-truth pose when each state of state_log was entered
        self._stops = StopOnsets()
        self.onsets = self._stops.onsets  # scan stamps from which the zone demanded a stop
        self.stop_points = []
        self.commands = []
        self.velocities = []  # (wall time, (vx, vy, wz)) of every HighCmd: the direction of the motion
        self.boxes = {}  # placed boxes: name -> (x, y, yaw, size_x, size_y)
        self.boxes_seen = {}
        self.box_contacts = []
        self.min_box_clearance = math.inf
        self._box_touching = set()
        self.avoidance = []  # the controller's avoidance events
        self.detours = []
        rospy.Subscriber("/rbd_sim/ground_truth", Odometry, self.on_truth, queue_size=50)
        rospy.Subscriber("/rbd_sim/obstacles", MarkerArray, self.on_people, queue_size=5)
        rospy.Subscriber("/rbd_controller/state", String, self.on_state, queue_size=20)
        rospy.Subscriber("/rbd_lidar/state", CollisionState, self.on_zone, queue_size=50)
        rospy.Subscriber("/rbd_controller/avoidance", String, self.on_avoidance, queue_size=50)
        from nav_msgs.msg import Path

        rospy.Subscriber("/rbd_controller/detour", Path, self.on_detour, queue_size=5)
        # every HighCmd the A1 receives (wall time, commanded speed)
        self.a1 = HighCmdMonitor(lcm_url, record=self.on_command, clock=time.time, record_velocity=self.on_velocity)

    def on_command(self, t, speed):
        """One HighCmd seen on LCM."""
        with self.lock:
            self.commands.append((t, speed))

    def on_velocity(self, t, velocity):
        """Direction of one HighCmd seen on LCM."""
        with self.lock:
            self.velocities.append((t, velocity))

    def on_truth(self, msg):
        """Ground-truth pose: path, contacts with people."""
        p = msg.pose.pose.position
        q = msg.pose.pose.orientation
        yaw = yaw_of(q)
        with self.lock:
            self.pose = (p.x, p.y, yaw)
            if not self.path or math.hypot(p.x - self.path[-1][0], p.y - self.path[-1][1]) > 0.01:
                self.path.append((p.x, p.y))
            people = [(n, x, y, r) for n, (x, y, r) in self.people.items()]
            self.contacts.update(msg.header.stamp.to_sec(), (p.x, p.y), yaw, people)
            touching = set()
            for name, (bx, by, byaw, sx, sy) in self.boxes.items():
                d = self._box_clearance((p.x, p.y), yaw, (bx, by), byaw, (sx, sy))
                self.min_box_clearance = min(self.min_box_clearance, d)
                if d <= 0.0:
                    touching.add(name)
                    if name not in self._box_touching:
                        self.box_contacts.append((msg.header.stamp.to_sec(), name))
            self._box_touching = touching

    def on_avoidance(self, msg):
        """The controller's avoidance events."""
        with self.lock:
            self.avoidance.append(msg.data)
        say("avoidance: %s" % msg.data)

    def on_detour(self, msg):
        """Planned detours (for the figure)."""
        with self.lock:
            self.detours.append([(q.pose.position.x, q.pose.position.y) for q in msg.poses])

    def on_people(self, msg):
        """Current people and obstacles of the simulated world."""
        with self.lock:
            for m in msg.markers:
                if m.ns == "placed_boxes":
                    if m.action == 0 and m.type == 1:  # ADD CUBE
                        q = m.pose.orientation
                        yaw = yaw_of(q)
                        self.boxes[m.text] = (m.pose.position.x, m.pose.position.y, yaw, m.scale.x, m.scale.y)
                        self.boxes_seen[m.text] = self.boxes[m.text]
                    elif m.action in (2, 3):
                        self.boxes.pop(m.text, None)
                    continue
                if m.action != 0 or m.type != 3:  # ADD, CYLINDER
                    if m.action in (2, 3):  # DELETE, DELETEALL
                        self.people.pop(m.text or "%s/%d" % (m.ns, m.id), None)
                    continue
                name = m.text or "%s/%d" % (m.ns, m.id)
                entry = (m.pose.position.x, m.pose.position.y, m.scale.x / 2.0)
                self.people[name] = entry
                self.people_log.setdefault(name, []).append(entry)

    def on_state(self, msg):
        """Main-controller state changes (printed, logged, stop points)."""
        with self.lock:
            self.state = msg.data
            self.state_log.append((time.time(), msg.data))
            self.state_poses.append(self.pose)
            if msg.data == "COLLISION_DETECTED" and self.pose:
                self.stop_points.append(self.pose[:2])
        say("state -> %s" % msg.data)

    def on_zone(self, msg):
        """Scan stamps from which the zone demanded a stop.

        A trick motion: any intruder; a guarded avoidance motion: an intruder on a side it heads
        towards (demo_report.stop_demanded).
        """
        stamp = msg.header.stamp.to_sec()
        with self.lock:
            velocity = next((v for t, v in reversed(self.velocities) if t <= stamp), (0.0, 0.0, 0.0))
            self._stops.update(stamp, msg.collision, msg.points, not msg.stale and not msg.error, velocity,
                               self.state)
            del self.velocities[:-200]

    def wait_state(self, states, timeout):
        """Block until the controller is in one of states; False on timeout."""
        return wait_for(lambda: self.state in states, timeout)

    def close(self):
        """Stop the LCM listener."""
        self.a1.close()


def states_since(monitor, n):
    """The controller states entered since the monitor's n-th logged state change."""
    with monitor.lock:
        return [state for _, state in monitor.state_log[n:]]


def wait_done(monitor, timeout):
    """Wait until the trick's queue is done (back to WAITING_FOR_GESTURE)."""
    return monitor.wait_state(("WAITING_FOR_GESTURE",), timeout)
