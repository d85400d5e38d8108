#!/usr/bin/env python3
"""rostest fault catalogue (issue 10, DESIGN §5): inject one fault while the robot walks a trick,
assert zero velocity at the A1 within the bound, clear the fault, assert recovery.

Measured on ground truth (/rbd_sim/ground_truth twist) and on the LCM_High_Cmd stream the mock
A1 receives. The faults are chosen with the private param ``~fault`` (one name, or several
separated by spaces, run in order on the same system, ``~repeat`` rounds; ``NAME:N`` runs that one
only in the last N rounds); every measurement is printed as one
``FAULT_RESULT {json}`` line (and appended to $RBD_FAULT_LOG if set) for docs/RELIABILITY.md.
``~sdk_layout`` (default 3.3.4) is the Unitree SDK layout the mock A1 was launched with: checked
on the wire (HighState size) and in the driver's diagnostics before any fault.
"""

import copy
import functools
import math
import os
import signal
import subprocess
import tempfile
import threading
import time
import unittest

import lcm
import rosgraph
import rospy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import Bool, Header, String
from std_srvs.srv import SetBool

import rbd_testkit
from rbd_bringup import a1_monitor
from rbd_geometry.rotation import yaw_of, yaw_to_quat
from rbd_msgs.srv import PressRemote
from rbd_testkit.ros import run_rostest, subscriber_nodes
from rbd_wire_oracle import unitree as vendor

#: The e-stop during a detour (AVOIDING) needs a stroll with a dropped bag (~60 s): with the other
#: avoidance system runs behind RBD_AVOIDANCE_EXPERIMENTS=1 (make test's serial lane is at its budget).
AVOIDANCE_EXPERIMENTS = bool(os.environ.get("RBD_AVOIDANCE_EXPERIMENTS"))
TRUTH_STILL = 0.02  # ground-truth speed below this is "stopped" [m/s, rad/s]
MOVING = 0.08  # ground-truth speed above this is "walking"


def speed_of_twist(t):
    return max(math.hypot(t.linear.x, t.linear.y), abs(t.angular.z))


# The kit's wait_for, ending early when ROS shuts down.
wait_for = functools.partial(rbd_testkit.wait_for, abort=rospy.is_shutdown)


def relay(pub, msg):
    """Publish from a callback or timer; at shutdown a publisher already closed is no error."""
    try:
        pub.publish(msg)
    except rospy.ROSException:
        if not rospy.core.is_shutdown_requested():
            raise


def fault_plan(spec, repeat):
    """The faults of ``spec`` ("a b:1 ...") round by round: a list of ``repeat`` lists of names.

    A plain name runs in every round, ``NAME:N`` in the last N rounds only; within a round the
    faults run in the order of ``spec`` (a fault that moves the robot's home, as estop_states'
    escape, runs in the last round only, so that the others' earlier rounds start where they
    always did).
    """
    rounds = [[] for _ in range(repeat)]
    for item in spec.split():
        name, _, n = item.partition(":")
        n = repeat if not n else int(n)
        if n < 1 or n > repeat:
            raise ValueError("%r: rounds must be 1..%d" % (item, repeat))
        for i in range(repeat - n, repeat):
            rounds[i].append(name)
    return rounds


def one_test_per_fault(case, spec, repeat):
    """A subclass of ``case`` with one test method per fault of ``spec`` instead of ``test_fault``.

    ``test_NAME`` runs fault NAME in each of its rounds of ``fault_plan(spec, repeat)`` (same
    round numbers in FAULT_RESULT); run_rostest shuffles the methods with RBD_TEST_SEED, so each
    fault must start from its own known state (every one starts by getting the robot walking, or
    waits for it to be idle), whichever ran before.
    """
    plan = fault_plan(spec, repeat)
    attrs = {"test_fault": None}  # not callable: not a test
    for item in spec.split():
        name = item.partition(":")[0]
        rounds = [i for i, faults in enumerate(plan) if name in faults]

        def test(self, name=name, rounds=rounds):
            self.wait_ready()
            for i in rounds:
                self.run_fault(name, i, repeat)

        attrs["test_" + name] = test
    return type(case.__name__, (case,), attrs)


def fault_names():
    """The names of the faults of ``~fault`` (without their round counts)."""
    return [item.partition(":")[0] for item in rospy.get_param("~fault").split()]


def children(pid):
    """PIDs of the child processes of ``pid`` (Linux /proc)."""
    out = []
    for task in os.listdir("/proc/%d/task" % pid):
        try:
            with open("/proc/%d/task/%s/children" % (pid, task)) as fh:
                out += [int(c) for c in fh.read().split()]
        except FileNotFoundError:  # the thread ended between listdir and open
            continue
    return out


def node_pid(name):
    """PID of a running ROS node (same host) from its XML-RPC API."""
    import xmlrpc.client

    uri = rosgraph.Master("/test_faults").lookupNode(name)
    code, _msg, pid = xmlrpc.client.ServerProxy(uri).getPid("/test_faults")
    if code != 1:
        raise RuntimeError("getPid(%s) failed" % name)
    return int(pid)


class Monitor:
    """Ground truth, controller state, relays for the cloud / pose / heartbeat, LCM command stream."""

    def __init__(self):
        self.lock = threading.Lock()
        self.truth = []  # (t, speed)
        self.pose = (0.0, 0.0, 0.0)  # latest ground-truth (x, y, yaw)
        self.poses = []  # (t, x, y, yaw) of ground truth
        self.commands = []  # (t, speed) of every HighCmd the A1 receives
        self.states = []  # (t, state)
        self.cloud_mode = "pass"  # pass | silent | malformed
        self.last_valid_cloud = None
        self.malformed_sent = 0
        self.pose_pass = True
        self.last_pose = None
        self.heartbeat = "operator_link" in fault_names()  # on from the start when tested
        self.diag = None  # the driver's last DiagnosticStatus
        self.remote_held = []  # (t, held) from /rbd_a1_driver/remote_estop_held
        self.cloud_pub = rospy.Publisher("/reliability/points", PointCloud2, queue_size=2)
        self.pose_pub = rospy.Publisher("/reliability/pose", PoseStamped, queue_size=5)
        self.hb_pub = rospy.Publisher("/rbd_local/heartbeat", Header, queue_size=2)
        self.hb_sent = 0  # heartbeats relayed so far
        self.gesture = rospy.Publisher("/rbd_gestrec/gesture", String, queue_size=10)
        rospy.Subscriber("/rbd_sim/ground_truth", Odometry, self.on_truth, queue_size=50)
        rospy.Subscriber("/rbd_controller/state", String, self.on_state, queue_size=20)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diag, queue_size=20)
        rospy.Subscriber("/rbd_a1_driver/remote_estop_held", Bool, self.on_remote, queue_size=20)
        faults = set(fault_names())
        if faults & {"lidar_silent", "lidar_malformed"}:  # rbd_lidar reads /reliability/points in these tests
            rospy.Subscriber("/ouster/points", PointCloud2, self.on_cloud, queue_size=2, buff_size=2 ** 24)
        if "pose_silent" in faults:  # the position controller follows /reliability/pose
            rospy.Subscriber("/rbd_sim/ground_truth_pose", PoseStamped, self.on_pose, queue_size=5)
        rospy.Timer(rospy.Duration(0.5), self.on_hb_timer)
        self.a1 = a1_monitor.HighCmdMonitor(rospy.get_param("/rbd_sim/lcm_url"), record=self.on_command)

    # ------------------------------------------------------------ inputs
    def on_command(self, t, speed):
        with self.lock:
            self.commands.append((t, speed))

    def on_truth(self, msg):
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        with self.lock:
            self.truth.append((time.monotonic(), speed_of_twist(msg.twist.twist)))
            self.pose = (p.x, p.y, yaw_of(q))
            self.poses.append((time.monotonic(),) + self.pose)

    def on_state(self, msg):
        with self.lock:
            self.states.append((time.monotonic(), msg.data))

    def on_diag(self, msg):
        for st in msg.status:
            if st.name == "rbd_a1_driver: A1 link":
                self.diag = {kv.key: kv.value for kv in st.values}

    def on_remote(self, msg):
        with self.lock:
            self.remote_held.append((time.monotonic(), msg.data))

    def on_cloud(self, msg):
        mode = self.cloud_mode
        if mode == "pass":
            relay(self.cloud_pub, msg)
            self.last_valid_cloud = time.monotonic()
        elif mode == "malformed":
            relay(self.cloud_pub, malformed(msg, self.malformed_sent))
            self.malformed_sent += 1

    def on_pose(self, msg):
        if self.pose_pass:
            relay(self.pose_pub, msg)
            self.last_pose = time.monotonic()

    def on_hb_timer(self, _event):
        if self.heartbeat:
            relay(self.hb_pub, Header(stamp=rospy.Time.now(), frame_id="test_faults"))
            self.hb_sent += 1

    def arm_heartbeat(self):
        """Turn the heartbeat on; wait for a beat sent while rbd_controller is connected (it arms the watchdog)."""
        n = self.hb_sent
        self.heartbeat = True
        rbd_testkit.wait_for(lambda: self.hb_sent > n and "/rbd_controller" in subscriber_nodes(self.hb_pub), 10.0,
                             what="a heartbeat sent to a connected rbd_controller")

    def close(self):
        self.a1.close()

    # ------------------------------------------------------------ queries
    @property
    def state(self):
        with self.lock:
            return self.states[-1][1] if self.states else ""

    def trick_started(self):
        """When the current trick's path was generated (its last GENERATING_PATH state); 0 if never."""
        with self.lock:
            return max([t for t, s in self.states if s == "GENERATING_PATH"] or [0.0])

    def speed(self):
        with self.lock:
            return self.truth[-1][1] if self.truth else 0.0

    def stop_delay(self, series, t0, t1, still):
        """Delay after t0 from which every sample of series up to t1 is below still; None if never."""
        with self.lock:
            samples = list(getattr(self, series))
        return a1_monitor.stop_delay(samples, t0, t1, still)

    def stop_episode(self, series, t0, t1, still, hold):
        """Delay after t0 of the first run of samples below still lasting >= hold; None if none."""
        with self.lock:
            samples = [(t, v) for t, v in getattr(self, series) if t0 <= t <= t1]
        start = None
        for t, v in samples:
            if v >= still:
                start = None
                continue
            if start is None:
                start = t
            if t - start >= hold:
                return max(0.0, start - t0)
        return None

    def max_speed(self, series, t0, t1):
        with self.lock:
            return max([v for t, v in getattr(self, series) if t0 <= t <= t1] or [0.0])

    def count(self, series, t0, t1):
        with self.lock:
            return len([1 for t, _v in getattr(self, series) if t0 <= t <= t1])


def malformed(msg, n):
    """A broken copy of an ouster-ros cloud; the kind rotates: no range field, truncated, blinded."""
    bad = copy.copy(msg)
    kind = n % 3
    if kind == 0:
        bad.fields = [f for f in msg.fields if f.name != "range"]
    elif kind == 1:
        bad.data = msg.data[: len(msg.data) // 2]
    else:
        bad.data = bytes(len(msg.data))  # every range 0: a blinded sensor
    return bad


class Faults(unittest.TestCase):
    """The faults of ``~fault`` in turn, ``~repeat`` rounds, on one simulated system."""

    @classmethod
    def setUpClass(cls):
        cls.m = Monitor()
        cls.results = []

    @classmethod
    def tearDownClass(cls):
        cls.m.close()

    # ------------------------------------------------------------ helpers
    def record(self, **result):
        result["fault"] = self.fault
        rospy.loginfo("FAULT_RESULT %s", a1_monitor.report_fault_result(result))

    def em_stop(self, engaged):
        rospy.wait_for_service("/rbd_controller/em_stop", 30.0)
        return rospy.ServiceProxy("/rbd_controller/em_stop", SetBool)(engaged)

    def collision(self, detected):
        rospy.wait_for_service("/rbd_controller/collision", 30.0)
        return rospy.ServiceProxy("/rbd_controller/collision", SetBool)(detected)

    def hold(self, seconds, what):
        """Wait ``seconds`` of ground truth that keeps arriving, the controller's state unchanged throughout.

        (A sleep would also pass with the simulation stalled; five new ground-truth samples prove it went on.)
        """
        m = self.m
        t = time.monotonic()
        rbd_testkit.stays_unchanged(lambda: m.state, lambda: m.count("truth", t, time.monotonic()) >= 5, hold=seconds,
                                    what="%s: the controller's state" % what, proof="five new ground-truth samples")

    def walk(self, timeout=45.0):
        """Get the robot walking a trick (release the e-stop, show 'walk'); fail if it never moves."""
        m = self.m
        last_gesture = [0.0]

        def walking():  # (the release and the gesture are sent from the predicate until the robot walks)
            if m.speed() > MOVING and m.state == "EXECUTING":
                return True
            if m.state == "EMERGENCY_STOP":
                self.em_stop(False)
            if m.state == "WAITING_FOR_GESTURE" and time.monotonic() - last_gesture[0] > 0.4:
                m.gesture.publish(String("walk"))
                last_gesture[0] = time.monotonic()
            return False

        if not wait_for(walking, timeout):
            self.fail("robot never walked: state %r, speed %.3f" % (m.state, m.speed()))

    def assert_stops(self, t0, bound_cmd, bound_truth, hold=2.0, lcm=True):
        """Zero velocity in the A1's commands within bound_cmd and on ground truth within bound_truth
        after t0, and still for hold seconds after; returns (cmd_delay, truth_delay)."""
        t1 = t0 + max(bound_cmd, bound_truth) + hold
        wait_for(lambda: False, t1 - time.monotonic() + 0.1)
        truth = self.m.stop_delay("truth", t0, t1, TRUTH_STILL)
        self.assertIsNotNone(truth, "ground truth never came to rest (max %.3f)" % self.m.max_speed("truth", t0, t1))
        self.assertLessEqual(truth, bound_truth)
        cmd = None
        if lcm:
            cmd = self.m.stop_delay("commands", t0, t1, 1e-6)
            self.assertIsNotNone(cmd, "the A1 still receives non-zero velocity commands")
            self.assertLessEqual(cmd, bound_cmd)
        return cmd, truth

    def assert_recovers(self, timeout=40.0):
        """After the fault clears the robot walks again (resumed trick, or a new one)."""
        t0 = time.monotonic()
        self.walk(timeout)
        return time.monotonic() - t0

    def wait_ready(self):
        self.assertTrue(wait_for(lambda: self.m.state and self.m.truth, 90.0), "system not up")
        self.assertTrue(wait_for(lambda: self.m.count("commands", 0, 1e12) > 10, 30.0), "no LCM HighCmd seen")
        layout = str(rospy.get_param("~sdk_layout", "3.3.4"))
        sizes = []
        lc = lcm.LCM(rospy.get_param("/rbd_sim/lcm_url"))
        sub = lc.subscribe("LCM_High_State", lambda _c, data: sizes.append(len(data)))
        try:
            self.assertTrue(wait_for(lambda: lc.handle_timeout(50) or len(sizes) > 5, 10.0, step=0.0))
        finally:
            lc.unsubscribe(sub)
        self.assertEqual(set(sizes), {vendor.HIGH_STATES[layout].size}, "the mock A1 does not speak SDK %s" % layout)
        self.assertTrue(wait_for(lambda: (self.m.diag or {}).get("sdk_layout") == layout, 10.0),
                        "the driver did not detect SDK %s: %s" % (layout, self.m.diag))

    # ------------------------------------------------------------ the catalogue
    def test_fault(self):
        self.wait_ready()
        repeat = int(rospy.get_param("~repeat", 1))
        for i, faults in enumerate(fault_plan(rospy.get_param("~fault"), repeat)):
            for fault in faults:
                self.run_fault(fault, i, repeat)

    def run_fault(self, fault, i, repeat):
        """Fault ``fault`` in round ``i`` (of ``repeat``); an assertion names the fault and round."""
        self.fault = fault
        rospy.loginfo("fault %s, round %d of %d", fault, i + 1, repeat)
        try:
            getattr(self, "fault_" + fault)(i)
        except AssertionError as exc:  # several faults share a stack: say which one failed
            raise AssertionError("%s (round %d of %d): %s" % (fault, i + 1, repeat, exc)) from exc

    def fault_lidar_silent(self, i):
        m = self.m
        self.walk()
        m.cloud_mode = "silent"
        t0 = m.last_valid_cloud
        # 3 scan periods (0.3 s) + detection/service/latency margin on a loaded host
        cmd, truth = self.assert_stops(t0, 1.0, 1.5)
        m.cloud_mode = "pass"
        rec = self.assert_recovers()
        self.record(run=i, cmd_stop_s=cmd, truth_stop_s=truth, recovery_s=rec, bound_s=1.0)

    def fault_lidar_malformed(self, i):
        m = self.m
        self.walk()
        m.cloud_mode = "malformed"
        t0 = m.last_valid_cloud
        cmd, truth = self.assert_stops(t0, 1.0, 1.5)
        self.assertGreater(m.malformed_sent, 5)
        m.cloud_mode = "pass"
        rec = self.assert_recovers()
        self.record(run=i, cmd_stop_s=cmd, truth_stop_s=truth, recovery_s=rec, bound_s=1.0)

    def fault_pose_silent(self, i):
        m = self.m
        self.walk()
        m.pose_pass = False
        t0 = m.last_pose
        # pose_timeout 0.5 s + margin
        cmd, truth = self.assert_stops(t0, 1.2, 1.7)
        m.pose_pass = True
        rec = self.assert_recovers()
        self.record(run=i, cmd_stop_s=cmd, truth_stop_s=truth, recovery_s=rec, bound_s=1.2)

    def fault_link_silent(self, i):
        m = self.m
        self.walk()
        # The driver and its keep-alive process freeze: nothing reaches the A1 any more.
        pids = [node_pid("/rbd_a1_driver")]
        pids += children(pids[0])
        for pid in pids:
            os.kill(pid, signal.SIGSTOP)
        t0 = time.monotonic()
        try:
            # mock A1's own watchdog: cmd_timeout 0.1 s + latency 0.05 s + margin
            _cmd, truth = self.assert_stops(t0, 1.0, 1.0, lcm=False)
            silent = m.count("commands", t0 + 0.3, t0 + 2.0)
        finally:
            for pid in pids:
                os.kill(pid, signal.SIGCONT)
        self.assertEqual(silent, 0, "the A1 still received commands: the link was not silent")
        rec = self.assert_recovers()
        self.record(run=i, truth_stop_s=truth, recovery_s=rec, bound_s=1.0)

    def fault_pos_controller_killed(self, i):
        self.walk()
        pid = node_pid("/rbd_pos_controller")
        os.kill(pid, signal.SIGSTOP)  # hung mid-motion: /cmd_vel stops
        t0 = time.monotonic()
        try:
            # the driver's cmd_vel timeout (0.25 s) + margin
            cmd, truth = self.assert_stops(t0, 1.0, 1.5, hold=1.0)
        finally:
            os.kill(pid, signal.SIGKILL)  # then it dies: respawned by roslaunch

        def respawned():
            try:
                return node_pid("/rbd_pos_controller") != pid
            except (OSError, RuntimeError, rosgraph.MasterError):
                return False  # old URI still registered / new one not up yet

        self.assertTrue(wait_for(respawned, 30.0, step=0.5), "not respawned")
        rec = self.assert_recovers(60.0)  # respawned position controller, trick goes on or restarts
        self.record(run=i, cmd_stop_s=cmd, truth_stop_s=truth, recovery_s=rec, bound_s=1.0)

    def fault_lidar_killed(self, i):
        self.walk()
        pid = node_pid("/rbd_lidar")
        os.kill(pid, signal.SIGKILL)  # the collision monitor dies; roslaunch respawns it after 1 s
        t0 = time.monotonic()
        # rbd_controller's lidar_timeout (0.5 s) + margin; the respawned monitor may release the
        # robot soon after, so look for a stop episode of >= 0.3 s starting within the bound
        wait_for(lambda: False, 2.0)
        cmd = self.m.stop_episode("commands", t0, t0 + 2.0, 1e-6, 0.3)
        truth = self.m.stop_episode("truth", t0, t0 + 2.0, TRUTH_STILL, 0.3)
        self.assertIsNotNone(cmd, "no zero-velocity episode at the A1 after the monitor died")
        self.assertIsNotNone(truth, "the robot did not come to rest after the monitor died")
        self.assertLessEqual(cmd, 1.0)
        self.assertLessEqual(truth, 1.5)

        def respawned():
            try:
                return node_pid("/rbd_lidar") != pid
            except (OSError, RuntimeError, rosgraph.MasterError):
                return False

        self.assertTrue(wait_for(respawned, 30.0, step=0.5), "rbd_lidar not respawned")
        rec = self.assert_recovers(60.0)
        self.record(run=i, cmd_stop_s=cmd, truth_stop_s=truth, recovery_s=rec, bound_s=1.0)

    def fault_controller_killed(self, i):
        m = self.m
        self.walk()
        with m.lock:
            n_states = len(m.states)
        os.kill(node_pid("/rbd_controller"), signal.SIGKILL)  # the position controller keeps driving
        t0 = time.monotonic()

        def respawned():
            with m.lock:
                return [t for t, s in m.states[n_states:] if s == "EMERGENCY_STOP"]

        self.assertTrue(wait_for(lambda: respawned(), 60.0), "controller did not come back in EMERGENCY_STOP")
        t_back = respawned()[0]
        # The driver's e-stop signal watchdog: no /rbd_controller/estop (republished at 10 Hz) for
        # estop_timeout 0.5 s => engaged. Bound from the kill: 0.1 + 0.5 + margin on a loaded host.
        # Still from then on: through the respawn and 3 s in EMERGENCY_STOP.
        t1 = max(t_back, t0 + 1.5) + 3.0
        wait_for(lambda: False, t1 - time.monotonic() + 0.1)
        cmd = m.stop_delay("commands", t0, t1, 1e-6)
        truth = m.stop_delay("truth", t0, t1, TRUTH_STILL)
        self.assertIsNotNone(cmd, "the A1 still receives non-zero velocity commands")
        self.assertIsNotNone(truth, "ground truth never came to rest (max %.3f)" % m.max_speed("truth", t0, t1))
        self.assertLessEqual(cmd, 1.0, "A1 commands not zero within 1.0 s of the kill")
        self.assertLessEqual(truth, 1.5, "ground truth not at rest within 1.5 s of the kill")
        self.assertLess(t0 + cmd, t_back, "zero only once the controller was back: the driver's gate did not act")
        self.assertEqual(m.state, "EMERGENCY_STOP")
        rec = self.assert_recovers()
        self.record(
            run=i,
            respawn_s=t_back - t0,
            cmd_stop_s=cmd,
            truth_stop_s=truth,
            recovery_s=rec,
            bound_s=1.0,
        )

    def fault_estop_states(self, i):
        """The e-stop in every state, each case from its known state, ordered so that the robot's
        trick has to end only once (at the start): the cases that need an idle robot (waiting,
        escaping, dodging, avoiding) first, then a fresh "walk" (caught in GENERATING_PATH) on
        which the cases that e-stop a walking robot run; it is left walking. First in its round
        (faults_nodes.test) it finds the robot in its power-up e-stop, released here; after another
        fault the robot's trick ends first."""
        m = self.m

        def idle():  # (a power-up e-stop, before any trick, is released from the predicate)
            if m.state == "EMERGENCY_STOP" and not m.trick_started():
                self.em_stop(False)
            return m.state == "WAITING_FOR_GESTURE"

        # WAITING_FOR_GESTURE (the trick the robot came with, if any, ends first)
        self.assertTrue(wait_for(idle, 60.0), "trick did not finish: %r" % m.state)
        t0 = time.monotonic()
        self.em_stop(True)
        cmd, truth = self.assert_stops(t0, 0.5, 1.0, hold=1.0)
        self.assertEqual(m.state, "EMERGENCY_STOP")
        self.em_stop(False)
        self.assertTrue(wait_for(lambda: m.state == "WAITING_FOR_GESTURE", 10.0))
        self.record(run=i, state="WAITING_FOR_GESTURE", cmd_stop_s=cmd, truth_stop_s=truth)
        self.estop_while_escaping(i)
        self.estop_while_dodging(i)
        if AVOIDANCE_EXPERIMENTS:
            self.estop_while_avoiding(i)
        # GENERATING_PATH (short-lived: try to catch it a few times), from idle; the cases below
        # e-stop the "walk" it starts
        caught = False
        for _ in range(4):
            self.assertTrue(wait_for(lambda: m.state == "WAITING_FOR_GESTURE", 60.0))
            m.gesture.publish(String("walk"))
            if wait_for(lambda: m.state != "WAITING_FOR_GESTURE", 5.0, step=0.002) and m.state == "GENERATING_PATH":
                t0 = time.monotonic()
                self.em_stop(True)
                cmd, truth = self.assert_stops(t0, 0.5, 1.0, hold=1.0)
                with m.lock:
                    seen = [s for _t, s in m.states[-2:]]
                self.assertEqual(seen[-1], "EMERGENCY_STOP")
                caught = seen == ["GENERATING_PATH", "EMERGENCY_STOP"]  # else EXECUTING came first
                self.em_stop(False)
                self.assertTrue(wait_for(lambda: m.speed() > MOVING, 20.0), "no walk after release")
                self.record(run=i, state="GENERATING_PATH", cmd_stop_s=cmd, truth_stop_s=truth, caught=caught)
                break
            wait_for(lambda: m.state == "WAITING_FOR_GESTURE", 60.0)
        # EXECUTING
        self.walk()
        t0 = time.monotonic()
        self.em_stop(True)
        cmd, truth = self.assert_stops(t0, 0.5, 1.0)
        self.assertEqual(m.state, "EMERGENCY_STOP")
        self.em_stop(False)
        self.assertTrue(wait_for(lambda: m.speed() > MOVING, 20.0), "trick did not resume after release")
        self.record(run=i, state="EXECUTING", cmd_stop_s=cmd, truth_stop_s=truth)
        # COLLISION_DETECTED, then e-stop: e-stop wins, the collision clearing does not release it
        self.walk()
        self.collision(True)
        t0 = time.monotonic()
        cmd, truth = self.assert_stops(t0, 0.5, 1.0, hold=1.0)
        self.assertTrue(self.em_stop(True).success)
        # the service answers before /rbd_controller/state reaches this node: wait for it
        self.assertTrue(wait_for(lambda: m.state == "EMERGENCY_STOP", 30.0), m.state)
        self.collision(False)
        t1 = time.monotonic()
        self.hold(1.5, "collision cleared under an e-stop")
        self.assertEqual(m.state, "EMERGENCY_STOP")
        self.assertLess(m.max_speed("truth", t1, time.monotonic()), TRUTH_STILL)
        self.em_stop(False)
        self.assertTrue(wait_for(lambda: m.speed() > MOVING, 20.0), "trick did not resume")
        self.record(run=i, state="COLLISION_DETECTED", cmd_stop_s=cmd, truth_stop_s=truth)
        # collision and e-stop at once
        self.walk()
        threads = [
            threading.Thread(target=self.collision, args=(True,)),
            threading.Thread(target=self.em_stop, args=(True,)),
        ]
        t0 = time.monotonic()
        for th in threads:
            th.start()
        for th in threads:
            th.join(10.0)
        cmd, truth = self.assert_stops(t0, 0.5, 1.0, hold=1.0)
        self.assertEqual(m.state, "EMERGENCY_STOP")
        self.em_stop(False)  # collision still set: stays stopped
        self.assertTrue(wait_for(lambda: m.state == "COLLISION_DETECTED", 5.0), m.state)
        t1 = time.monotonic()
        self.hold(1.0, "e-stop released with the collision still set")
        self.assertLess(m.max_speed("truth", t1, time.monotonic()), TRUTH_STILL)
        self.collision(False)
        self.assertTrue(wait_for(lambda: m.speed() > MOVING, 20.0), "trick did not resume")
        self.record(run=i, state="COLLISION+ESTOP", cmd_stop_s=cmd, truth_stop_s=truth)

    def estop_while_escaping(self, i):
        """Issue 17: the e-stop preempts an avoidance motion as it preempts a trick.

        A wall panel goes up 0.45 m ahead of the idle robot: the zone stops it, the wall is
        classified static and the robot steps back (ESCAPING, a guarded translation). Mid-step the
        e-stop is engaged: zero velocity at the A1 and on ground truth within the same bounds as for
        a trick; nothing moves while engaged; after the release the escape goes on.
        """
        from rbd_msgs.srv import PlaceBox

        m = self.m
        self.assertTrue(wait_for(lambda: m.state == "WAITING_FOR_GESTURE", 60.0), "trick did not finish")
        with m.lock:
            x, y, yaw = m.pose
        place = rospy.ServiceProxy("/rbd_sim/place_box", PlaceBox)
        place(name="wall", x=x + 0.5 * math.cos(yaw), y=y + 0.5 * math.sin(yaw), yaw=yaw, size_x=0.1, size_y=2.0,
              height=1.0, remove=False)
        try:
            self.assertTrue(wait_for(lambda: m.state == "ESCAPING" and m.speed() > 0.05, 30.0),
                            "no escape from the wall: state %r" % m.state)
            t0 = time.monotonic()
            self.em_stop(True)
            cmd, truth = self.assert_stops(t0, 0.5, 1.0, hold=1.5)
            self.assertEqual(m.state, "EMERGENCY_STOP")
            self.em_stop(False)
            self.assertTrue(wait_for(lambda: m.state == "WAITING_FOR_GESTURE", 60.0),
                            "the escape did not finish after the release: %r" % m.state)
            with m.lock:
                end = m.pose
            # It stepped back, away from the wall (never towards it).
            self.assertLess((end[0] - x) * math.cos(yaw) + (end[1] - y) * math.sin(yaw), -0.15)
            self.record(run=i, state="ESCAPING", cmd_stop_s=cmd, truth_stop_s=truth)
        finally:
            place(name="wall", remove=True)

    def along(self, origin):
        """Ground-truth distance of the robot ahead of origin (x, y, yaw), along its heading [m]."""
        with self.m.lock:
            x, y, _ = self.m.pose
        return (x - origin[0]) * math.cos(origin[2]) + (y - origin[1]) * math.sin(origin[2])

    def estop_while_dodging(self, i):
        """Issue 17: the e-stop preempts a dodge (DODGING, a guarded step away from a visitor).

        With ``~dodge`` on, a visitor walks at the idle robot at 0.5 m/s; once it steps back the
        e-stop is engaged: zero velocity at the A1 and on ground truth within a trick's bounds, and
        still while engaged although the visitor stands 0.6 m ahead; after the release (the visitor
        gone) it returns home.
        """
        from rbd_msgs.srv import PlaceObstacle

        m = self.m
        self.assertTrue(wait_for(lambda: m.state == "WAITING_FOR_GESTURE", 60.0), "not idle: %r" % m.state)
        self.rehome()  # the escape left it ~0.4 m behind its home: no room within ~dodge_max (0.5 m)
        with m.lock:
            home = m.pose
        place = rospy.ServiceProxy("/rbd_sim/place_obstacle", PlaceObstacle)
        rospy.set_param("/rbd_controller/dodge", True)

        def dodging():  # stepping back, mid-step (the step is ~dodge_step, 0.3 m)
            return m.state == "DODGING" and m.speed() > 0.05 and self.along(home) < -0.05

        try:
            time.sleep(1.3)  # the controller re-reads ~dodge every second
            d = 2.2
            while d > 0.6 and not dodging():
                place(name="visitor", x=home[0] + d * math.cos(home[2]), y=home[1] + d * math.sin(home[2]),
                      radius=0.22, height=1.7, remove=False)
                d -= 0.5 * 0.05
                time.sleep(0.05)
            self.assertTrue(wait_for(dodging, 10.0), "no step back from the visitor: state %r, %.2f m from home"
                            % (m.state, self.along(home)))
            t0 = time.monotonic()
            self.em_stop(True)
            cmd, truth = self.assert_stops(t0, 0.5, 1.0, hold=1.5)
            self.assertEqual(m.state, "EMERGENCY_STOP")
            place(name="visitor", remove=True)
            self.em_stop(False)
            self.assertTrue(wait_for(lambda: m.state == "WAITING_FOR_GESTURE" and abs(self.along(home)) < 0.08, 40.0),
                            "no return home after the release: %r, %.2f m" % (m.state, self.along(home)))
            self.record(run=i, state="DODGING", cmd_stop_s=cmd, truth_stop_s=truth)
        finally:
            place(name="visitor", remove=True)
            rospy.set_param("/rbd_controller/dodge", False)

    def goto(self, x, y, yaw):
        """Walk the idle robot to a world pose (position controller) and make it home (e-stop, release)."""
        from geometry_msgs.msg import Pose

        from rbd_msgs.srv import SetPosition

        m = self.m
        goal = Pose()
        goal.position.x, goal.position.y = x, y
        _x, _y, goal.orientation.z, goal.orientation.w = yaw_to_quat(yaw)
        rospy.ServiceProxy("/rbd_pos_controller/set_position", SetPosition)(pose=goal)

        def there():
            with m.lock:
                px, py, pyaw = m.pose
            return math.hypot(px - x, py - y) < 0.05 and abs(math.sin((pyaw - yaw) / 2.0)) < 0.03

        self.assertTrue(wait_for(there, 40.0), "the robot did not get to (%.1f, %.1f)" % (x, y))
        self.rehome()

    def rehome(self):
        """E-stop and release where the idle robot stands: its new home (as an operator who moved it)."""
        m = self.m
        self.em_stop(True)
        self.assertTrue(wait_for(lambda: m.state == "EMERGENCY_STOP", 5.0))
        self.em_stop(False)
        self.assertTrue(wait_for(lambda: m.state == "WAITING_FOR_GESTURE", 10.0))

    def estop_while_avoiding(self, i):
        """Issue 17: the e-stop preempts a detour (AVOIDING) as it preempts a trick.

        From the lab's free middle (1, 0) facing -x (as tests/experiments' box run), the robot strolls
        2 m out and back; a 0.4 m bag is dropped 0.5 m ahead of its footprint right after the start.
        It stops, classifies the bag static, steps back and plans a detour; while it walks the
        detour the e-stop is engaged: zero velocity at the A1 and on ground truth within a trick's
        bounds; after the release the detour goes on to its end without touching the bag, then the
        bag is taken away and the stroll completes.
        """
        from nav_msgs.msg import Path

        from rbd_bringup.metrics import box_ahead, footprint_box_clearance
        from rbd_msgs.srv import PlaceBox

        m = self.m
        self.assertTrue(wait_for(lambda: m.state == "WAITING_FOR_GESTURE", 60.0), "not idle: %r" % m.state)
        with m.lock:
            home = m.pose
        place = rospy.ServiceProxy("/rbd_sim/place_box", PlaceBox)
        detours = []  # arrival times of /rbd_controller/detour (a planned detour)
        detour_sub = rospy.Subscriber("/rbd_controller/detour", Path, lambda _msg: detours.append(time.monotonic()))
        try:
            self.goto(1.0, 0.0, math.pi)
            with m.lock:
                start = m.pose
            shown = [0.0]

            def strolling():
                if m.state == "WAITING_FOR_GESTURE" and time.monotonic() - shown[0] > 0.5:
                    m.gesture.publish(String("stroll"))  # shown until taken, as the operator does
                    shown[0] = time.monotonic()
                return m.state == "EXECUTING" and m.speed() > 0.15 and self.along(start) > 0.1

            self.assertTrue(wait_for(strolling, 30.0, 0.02), "the stroll did not start: %r" % m.state)
            with m.lock:
                robot = m.pose
            bag = box_ahead(robot, 0.5, (0.4, 0.4))
            t_bag = time.monotonic()
            place(name="bag", x=bag[0], y=bag[1], yaw=bag[2], size_x=0.4, size_y=0.4, height=0.4, remove=False)
            # Walking the planned detour: AVOIDING after the plan was published (not the escape's run-out).
            self.assertTrue(wait_for(lambda: detours and m.state == "AVOIDING" and m.speed() > 0.05
                                     and time.monotonic() - detours[-1] > 0.5, 60.0),
                            "no detour walked around the bag: state %r, %d plan(s)" % (m.state, len(detours)))
            t0 = time.monotonic()
            self.em_stop(True)
            cmd, truth = self.assert_stops(t0, 0.5, 1.0, hold=1.5)
            self.assertEqual(m.state, "EMERGENCY_STOP")
            self.em_stop(False)
            self.assertTrue(wait_for(lambda: m.state == "AVOIDING" and m.speed() > 0.05, 20.0),
                            "the detour did not go on after the release: %r" % m.state)
            # to its end (DETOUR_DONE or GIVE_UP -> EXECUTING; a collision stop on the way resumes AVOIDING)
            self.assertTrue(wait_for(lambda: m.state in ("EXECUTING", "WAITING_FOR_GESTURE"), 60.0),
                            "the detour did not end: %r" % m.state)
            with m.lock:
                path = [p for p in m.poses if p[0] >= t_bag]
            clearance = min(footprint_box_clearance((x, y), yaw, bag[:2], bag[2], (0.4, 0.4)) for _t, x, y, yaw in path)
            self.assertGreater(clearance, 0.0, "the robot touched the bag")
            self.record(run=i, state="AVOIDING", cmd_stop_s=cmd, truth_stop_s=truth, bag_clearance_m=clearance)
        finally:
            place(name="bag", remove=True)
            detour_sub.unregister()
        self.assertTrue(wait_for(lambda: m.state == "WAITING_FOR_GESTURE", 60.0), "the stroll did not finish")
        self.goto(home[0], home[1], home[2])

    def fault_remote_estop(self, i):
        """L2 + B on the A1's own remote while the robot walks: zero velocity at the A1 from the HighCmd
        after the HighState that carries the press (measured on lcm-logger's receive times), the robot
        at rest on ground truth, the controller in EMERGENCY_STOP; releases refused while held, nothing
        released by letting go, the operator's release resumes the trick."""
        m = self.m
        press = rospy.ServiceProxy("/rbd_sim/remote", PressRemote)
        rospy.wait_for_service("/rbd_sim/remote", 10.0)
        self.walk()
        log = os.path.join(tempfile.mkdtemp(prefix="faults_remote."), "lcm.log")
        logger = subprocess.Popen(["lcm-logger", "-q", "-f", "--flush-interval=50", "-l",
                                   rospy.get_param("/rbd_sim/lcm_url"), "-c", "LCM_High_.*", log])
        try:
            # the logger is up: it has written (with --flush-interval) this A1's HighCmds
            wait_for(lambda: os.path.exists(log) and os.path.getsize(log) > 0, 10.0, what="lcm-logger writing %s" % log)
            hold = 4.0
            with m.lock:
                n_held = len(m.remote_held)  # an earlier round's press and let-go are before this
            t0 = time.monotonic()
            self.assertTrue(press(["L2", "B"], hold).success)
            cmd, truth = self.assert_stops(t0, 0.5, 1.0, hold=1.0)
            self.assertTrue(wait_for(lambda: m.state == "EMERGENCY_STOP", 30.0), "controller not told: %s" % m.state)
        finally:
            logger.send_signal(signal.SIGINT)
            logger.wait(10.0)
        events = []
        reader = lcm.EventLog(log, "r")
        for e in reader:
            events.append((e.timestamp * 1e-6, e.channel, e.data))
        reader.close()
        layout = vendor.HIGH_STATES[str(rospy.get_param("~sdk_layout", "3.3.4"))]
        t_packet = next(t for t, ch, d in events if ch == "LCM_High_State" and len(d) == layout.size
                        and vendor.buttons_held(vendor.unpack(layout, d)["wirelessRemote"]) == ["L2", "B"])
        after = [(t, vendor.unpack(vendor.HIGH_CMD, d)) for t, ch, d in events if ch == "LCM_High_Cmd" and t > t_packet]
        first_zero = next(k for k, (_t, c) in enumerate(after)
                          if tuple(c["velocity"]) == (0.0, 0.0) and c["yawSpeed"] == 0.0)
        packet_to_zero = after[first_zero][0] - t_packet
        self.assertLessEqual(first_zero, 1, "%d HighCmd still moving after the press reached the A1" % first_zero)
        self.assertLess(packet_to_zero, 0.015)
        # While the buttons are held: the operator's release is refused, nothing moves.
        res = self.em_stop(False)
        self.assertFalse(res.success)
        self.assertIn("remote", res.message)
        t1 = time.monotonic()
        self.hold(0.5, "release refused while the remote is held")
        self.assertEqual(m.state, "EMERGENCY_STOP")
        # Let go: still stopped (the input arrived: remote_estop_held went true, then false, for
        # this press; the flag is latched and sent on change, so an earlier round's false is no proof).
        def let_go():
            with m.lock:
                held = [h for _t, h in m.remote_held[n_held:]]
            return True in held and held[-1] is False

        self.assertTrue(wait_for(let_go, hold + 3.0), "the remote never let go")
        self.hold(1.0, "the remote let go")
        self.assertEqual(m.state, "EMERGENCY_STOP")
        self.assertLess(m.max_speed("truth", t1, time.monotonic()), TRUTH_STILL)
        self.assertLess(m.max_speed("commands", t1, time.monotonic()), 1e-6)
        # The operator's release.
        self.assertTrue(self.em_stop(False).success)
        self.assertTrue(wait_for(lambda: m.speed() > MOVING, 20.0), "trick did not resume after the release")
        self.record(run=i, state="EXECUTING", packet_to_zero_ms=packet_to_zero * 1e3, moving_after_packet=first_zero,
                    cmd_stop_s=cmd, truth_stop_s=truth)

    def fault_operator_link(self, i):
        m = self.m
        if not m.heartbeat:
            m.arm_heartbeat()
        # A fresh trick ("walk": its first pose takes ~6 s, longer than the heartbeat timeout), so
        # neither the end of a trick nor the pause between two poses can pass for the watchdog's
        # stop: after another fault's recovery the robot may be anywhere in a trick. A trick
        # younger than 1.5 s will do (controller_killed's recovery starts one); an older one is
        # let finish first.
        def idle_or_fresh():
            if m.state in ("WAITING_FOR_GESTURE", "EMERGENCY_STOP"):
                return True
            return m.state == "EXECUTING" and time.monotonic() - m.trick_started() < 1.5

        self.assertTrue(wait_for(idle_or_fresh, 60.0), m.state)
        self.walk()
        m.heartbeat = False
        t0 = time.monotonic()
        timeout = float(rospy.get_param("/rbd_controller/operator_timeout"))
        cmd, truth = self.assert_stops(t0, timeout + 1.5, timeout + 2.0)
        self.assertGreater(truth, timeout - 0.6, "stopped before the heartbeat timed out: not the watchdog")
        self.assertEqual(m.state, "OPERATOR_LOST")
        m.heartbeat = True
        self.assertTrue(wait_for(lambda: m.state == "EXECUTING", 5.0), m.state)
        self.assertTrue(wait_for(lambda: m.speed() > MOVING, 20.0), "trick did not resume with the heartbeat")
        self.record(run=i, cmd_stop_s=cmd, truth_stop_s=truth, timeout_s=timeout)


if __name__ == "__main__":
    rospy.init_node("test_faults")
    run_rostest("rbd_bringup", rospy.get_param("~suite", "faults_" + fault_names()[0]), Faults)
