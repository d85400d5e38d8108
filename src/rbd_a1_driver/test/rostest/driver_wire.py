#!/usr/bin/env python3
"""rostest node: a fake A1 LCM server around the real rbd_a1_driver; every byte through the vendor's tables.

The fake server assembles HighState packets of both SDK layouts from ``rbd_wire_oracle`` (vendor
offsets) and reads the driver's HighCmd packets back through the same tables; nothing here
imports the driver's layout module. Before it starts the driver (``roslaunch
rbd_a1_driver.launch``) it starts ``lcm-logger``, which records every LCM packet with its kernel
receive time, so the whole HighCmd stream from the driver's first packet on is on record. A
minimal reference sender (its own process, nothing but a 2 ms LCM loop) is logged beside it:
when the machine itself stalls (this is a shared 2-core machine), the reference falls silent too,
which tells a stall of the machine from a pause of the driver. A 10 Hz e-stop flag stands in for
rbd_controller (as in the real system, the driver's e-stop watchdog is armed).
"""

import functools
import math
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
import unittest
import xmlrpc.client

import lcm
import rosgraph
import rosnode
import rospy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu, JointState
from std_msgs.msg import Bool, String

import rbd_testkit
from rbd_msgs.srv import SetBodyPose
from rbd_testkit.ros import RosoutWatcher, run_rostest
from rbd_wire_oracle import unitree as vendor

PKG = "rbd_a1_driver"
HIGH_CMD, HIGH_STATE = "LCM_High_Cmd", "LCM_High_State"
REFERENCE = "RBD_TEST_REFERENCE"
REFERENCE_SENDER = """
import sys, time, lcm
lc = lcm.LCM(sys.argv[1])
t = time.monotonic()
while True:
    lc.publish("%s", b"r")
    t += 0.002
    time.sleep(max(0.0, t - time.monotonic()))
""" % REFERENCE
SEND_RATE = 250.0  # the driver's default
KEEPALIVE_GAP = 0.020  # lcm_server_high exits after 10 loops of 2 ms without a command
KEEPALIVE_HOLD = 0.05  # the driver's ~keepalive_hold: its last command repeated this long, then zero velocity
NOMINAL = dict(
    mode=2,
    gaitType=1,
    imu={"quaternion": (1.0, 0.0, 0.0, 0.0), "accelerometer": (0.0, 0.0, 9.81)},
    bodyHeight=0.28,
    footForce=(29, 30, 31, 32),
)


def state_packet(layout="3.3.4", **values):
    """A HighState of an SDK layout, assembled from the vendor table (NOMINAL + values)."""
    v = dict(NOMINAL)
    v.update(values)
    return vendor.pack(vendor.HIGH_STATES[layout], v)


def twist(vx=0.0, vy=0.0, wz=0.0):
    t = Twist()
    t.linear.x, t.linear.y, t.angular.z = vx, vy, wz
    return t


def press_time(events, since):
    """Logger time of the first 3.3.4 HighState after ``since`` (wall s) with L2 + B held on the remote."""
    return next(t for t, ch, data in events if ch == HIGH_STATE and t > since and len(data) == 1025
                and vendor.buttons_held(vendor.unpack(vendor.HIGH_STATE_V334, data)["wirelessRemote"]) == ["L2", "B"])


def still(c):
    return tuple(c["velocity"]) == (0.0, 0.0) and c["yawSpeed"] == 0.0


# The test kit's wait_for at 50 Hz, ending early when ROS shuts down.
wait_for = functools.partial(rbd_testkit.wait_for, step=0.02, abort=rospy.is_shutdown)


def read_log(path):
    """(time [s], channel, data) of every complete event in an LCM log (may still be written)."""
    events = []
    log = lcm.EventLog(path, "r")
    try:
        for e in log:
            events.append((e.timestamp * 1e-6, e.channel, e.data))
    except (OSError, ValueError):
        pass  # a partly written last event
    finally:
        log.close()
    return events


class DriverWire(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("driver_wire")
        cls.url = rospy.get_param("~lcm_url")
        cls.lock = threading.Lock()
        cls.cmds = []  # (monotonic time, HighCmd as a dict of SDK members)
        cls.bad = []
        cls.packet = state_packet()
        cls.state_on = True
        cls.estop_value = False  # the stand-in controller's flag, published at 10 Hz
        cls.estop_on = True
        cls.estop_lock = threading.Lock()  # one publisher of the flag at a time (set_estop / _controller)
        cls.running = True
        cls.tmp = tempfile.mkdtemp(prefix="driver_wire.")
        cls.log_path = os.path.join(cls.tmp, "lcm.log")
        cls.logger = subprocess.Popen(["lcm-logger", "-q", "-f", "--flush-interval=50", "-l", cls.url,
                                       "-c", "LCM_High_.*|" + REFERENCE, cls.log_path], start_new_session=True)
        cls.reference = subprocess.Popen([sys.executable, "-c", REFERENCE_SENDER, cls.url], start_new_session=True)
        # The logger is up and recording once the reference sender's packets are in its file.
        wait_for(lambda: any(ch == REFERENCE for _, ch, _ in read_log(cls.log_path)), 30.0,
                 what="lcm-logger recording the reference sender", ignore=(OSError,))
        cls.lc = lcm.LCM(cls.url)
        cls.lc.subscribe(HIGH_CMD, cls._on_cmd)
        cls.pub = rospy.Publisher("/cmd_vel", Twist, queue_size=5)
        cls.estop = rospy.Publisher("/rbd_controller/estop", Bool, queue_size=1, latch=True)
        cls.status = rospy.Publisher("/rbd_pos_controller/status", String, queue_size=1, latch=True)
        cls.diag = []
        cls.joints = []
        cls.remote_held = []
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.diag.append)
        rospy.Subscriber("/joint_states", JointState, cls.joints.append)
        rospy.Subscriber("/rbd_a1_driver/remote_estop_held", Bool, lambda m: cls.remote_held.append(m.data))
        cls.rosout = RosoutWatcher()  # the driver's log lines prove that an e-stop flag reached it
        for target in (cls._rx, cls._tx, cls._controller):
            th = threading.Thread(target=target)
            th.daemon = True
            th.start()
        master = rosgraph.Master("/driver_wire")
        cls.driver_started = time.time()
        cls.driver = subprocess.Popen(["roslaunch", "rbd_a1_driver", "rbd_a1_driver.launch", "lcm_url:=" + cls.url,
                                       "send_rate:=%d" % SEND_RATE], start_new_session=True)
        master_lookup = functools.partial(master.lookupNode, "/rbd_a1_driver")
        rbd_testkit.wait_for(master_lookup, 120.0, step=0.01, what="rbd_a1_driver registered with the master",
                             ignore=(rosgraph.MasterError, OSError))
        cls.driver_registered = time.time()
        rospy.wait_for_message("/rbd_a1_driver/odom", Odometry, timeout=60.0)
        wait_for(lambda: cls.pub.get_num_connections() > 0, 30.0)
        cls.rosout.wait_connected("/rbd_a1_driver")

    @classmethod
    def tearDownClass(cls):
        cls.running = False
        for proc in (cls.driver, cls.reference, cls.logger):
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGINT)
                try:
                    proc.wait(15.0)
                except subprocess.TimeoutExpired:
                    os.killpg(proc.pid, signal.SIGKILL)
                    proc.wait()

    # ---- the fake A1 server and the stand-in controller ----------------------------------------
    @classmethod
    def _on_cmd(cls, channel, data):
        try:
            cmd = vendor.unpack(vendor.HIGH_CMD, data)
        except ValueError as e:
            cls.bad.append(str(e))
            return
        if cmd["levelFlag"] != vendor.HIGHLEVEL:
            cls.bad.append("levelFlag %r" % cmd["levelFlag"])
        with cls.lock:
            cls.cmds.append((time.monotonic(), cmd))
            del cls.cmds[:-3000]

    @classmethod
    def _rx(cls):
        while cls.running:
            cls.lc.handle_timeout(100)

    @classmethod
    def _tx(cls):
        cls._every(200.0, lambda: cls.state_on and cls.lc.publish(HIGH_STATE, cls.packet))

    @classmethod
    def _controller(cls):
        def flag():
            with cls.estop_lock:
                if cls.estop_on:
                    cls.estop.publish(Bool(cls.estop_value))

        cls._every(10.0, flag)

    @classmethod
    def _every(cls, hz, action):
        """Run ``action`` at ``hz`` until the class ends (a sender's pace: rospy.Rate keeps the schedule)."""
        rate = rospy.Rate(hz)
        try:
            while cls.running and not rospy.is_shutdown():
                action()
                rate.sleep()
        except rospy.ROSInterruptException:
            pass

    def set_estop(self, value):
        """Set the stand-in controller's flag and publish it now (then at 10 Hz, as before)."""
        with self.estop_lock:
            DriverWire.estop_value = value
            if DriverWire.estop_on:
                self.estop.publish(Bool(value))

    # ---- helpers ----------------------------------------------------------------------------------
    def setUp(self):
        """Known state: a live 3.3.4 robot, no buttons, e-stop released, no status."""
        DriverWire.packet = state_packet()
        DriverWire.state_on = True
        DriverWire.estop_on = True
        DriverWire.estop_value = False
        self.pub.publish(twist())
        self.assertTrue(wait_for(lambda: self.diag_value("remote_estop") in ("ready", "off"), 5.0)
                        or self.release_remote(), "remote e-stop still engaged from before")
        # The released flag must have reached the driver, not only be due on the 10 Hz thread's next
        # turn: a test that engaged it just before (LED colours) left the gate held, and a body pose
        # called at once was refused. No test sets the status "emergency": red LEDs = an e-stop held.
        self.set_estop(False)
        self.assertTrue(wait_for(lambda: self.leds() != [(0xC6, 0x28, 0x28)] * 4, 5.0),
                        "the driver still holds an e-stop from before: LEDs %s" % self.leds())

    def flag_taken(self, value):
        """Set the stand-in controller's flag and wait until the driver logs that it took it.

        The driver logs a change of the flag ("e-stop ENGAGED" / "e-stop released"), so ``value``
        must differ from the flag the driver holds.
        """
        mark = self.rosout.mark()
        self.set_estop(value)
        self.rosout.wait_for("e-stop ENGAGED" if value else "e-stop released", node="/rbd_a1_driver", since=mark,
                             timeout=30.0)

    def operator_release(self):
        """The operator's release: the controller's flag goes true (engaged), then false."""
        self.flag_taken(True)
        self.flag_taken(False)

    def release_remote(self):
        """The operator's release of a latched remote e-stop, once the driver has seen the buttons let go.

        A release while the driver still reads L2 + B held is void (as on the robot); after
        ``press(False)`` the driver may not yet have read a HighState without them (a loaded machine).
        """
        def let_go():
            try:  # a fresh subscription to the latched topic: the driver's value now
                return not rospy.wait_for_message("/rbd_a1_driver/remote_estop_held", Bool, timeout=2.0).data
            except rospy.ROSException:
                return False

        if not wait_for(let_go, 30.0):
            return False
        self.operator_release()
        return wait_for(lambda: self.diag_value("remote_estop") == "ready", 30.0)

    def last(self):
        with self.lock:
            return self.cmds[-1][1]

    def since(self, t0):
        with self.lock:
            return [(t, c) for t, c in self.cmds if t >= t0]

    def assert_still_since(self, t0, msg="moved"):
        """Commands were sent since t0 (the driver kept sending), and every one had zero velocity."""
        late = [c for t, c in self.since(t0)]
        self.assertTrue(late, "no HighCmd since t0: the driver stopped sending")
        self.assertTrue(all(still(c) for c in late), msg)

    def send(self, msg, duration, rate=20.0):
        t0 = t_pub = time.monotonic()
        pace = rospy.Rate(rate)
        while time.monotonic() - t0 < duration:
            t_pub = time.monotonic()
            self.pub.publish(msg)
            pace.sleep()
        return t_pub

    def status_now(self):
        return self.diag[-1].status[0] if self.diag else None

    def diag_value(self, key):
        st = self.status_now()
        if st is None:
            return None
        return {kv.key: kv.value for kv in st.values}.get(key)

    def fresh_diag(self, timeout=3.0):
        """The first diagnostics published after now."""
        n = len(self.diag)
        self.assertTrue(wait_for(lambda: len(self.diag) > n, timeout), "no /diagnostics")
        return self.diag[-1].status[0]

    def drive_until(self, msg, predicate, timeout=5.0):
        """Publish ``msg`` at 20 Hz until the last HighCmd satisfies ``predicate`` (True) or ``timeout``."""
        def published_and_seen():
            self.pub.publish(msg)
            return predicate(self.last())

        return bool(wait_for(published_and_seen, timeout, step=0.05))

    def walks(self, timeout=5.0):
        """cmd_vel 0.3 m/s until a HighCmd carries it (True) or ``timeout`` s pass."""
        return self.drive_until(twist(0.3), lambda c: abs(c["velocity"][0] - 0.3) < 1e-5, timeout)

    def walk(self, msg="the driver does not walk on cmd_vel"):
        self.assertTrue(self.walks(), msg)

    def events_until(self, t_wall, timeout=10.0):
        """Every event of the LCM log once it holds the reference sender's packets up to ``t_wall``
        (after ``timeout``: the log as it is)."""
        events = []

        def recorded():
            events[:] = read_log(self.log_path)
            return any(ch == REFERENCE and t >= t_wall for t, ch, _ in events[-200:])

        wait_for(recorded, timeout, step=0.05)
        return events

    # ---- HighCmd on the wire ----------------------------------------------------------------------
    def test_every_packet_is_a_vendor_high_cmd(self):
        self.assertTrue(wait_for(lambda: len(self.cmds) > 20, 5.0))
        self.assertEqual(self.bad, [])

    def test_cmd_vel_reads_back_as_mode_2_with_the_commanded_velocity(self):
        def commanded(c):
            return (c["mode"], c["gaitType"]) == (vendor.MODE_VELOCITY_WALK, vendor.GAIT_TROT) and all(
                abs(a - b) < 1e-5 for a, b in zip(tuple(c["velocity"]) + (c["yawSpeed"],), (0.3, 0.1, 0.2)))

        self.assertTrue(self.drive_until(twist(0.3, 0.1, 0.2), commanded), "not mode 2 / trot / 0.3, 0.1, 0.2: %s"
                        % self.last())

    def test_clamped(self):
        def clamped(c):
            return all(abs(a - b) < 1e-5 for a, b in zip(tuple(c["velocity"]) + (c["yawSpeed"],), (0.5, -0.3, 1.0)))

        self.assertTrue(self.drive_until(twist(5.0, -5.0, 9.0), clamped), "not clamped: %s" % self.last())

    def test_zero_after_025s_without_cmd_vel(self):
        """Measured from the HighCmd that first carries the last cmd_vel (its arrival at the driver) to
        the first zero one, on the logger's receive times: the 0.25 s cmd_timeout, not the transport."""
        self.walk()
        t0 = time.time()
        self.pub.publish(twist(0.31))  # the last one, recognisable on the wire
        cmds = []

        def zero_and_after():
            """The HighCmds since t0 once the log holds the 0.31 one, a zero one after it and 0.5 s more."""
            cmds[:] = [(t, vendor.unpack(vendor.HIGH_CMD, d)) for t, ch, d in read_log(self.log_path)
                       if ch == HIGH_CMD and t > t0]
            t_last = next((t for t, c in cmds if abs(c["velocity"][0] - 0.31) < 1e-6), None)
            t_zero = t_last and next((t for t, c in cmds if t > t_last and still(c)), None)
            return t_zero and cmds[-1][0] > t_zero + 0.5 and (t_last, t_zero)

        t_last, t_zero = wait_for(zero_and_after, 10.0, step=0.1,
                                  what="the 0.31 m/s HighCmd, a zero one and 0.5 s after it")
        rospy.loginfo("MEASURED zero velocity %.3f s after the last cmd_vel reached the driver", t_zero - t_last)
        self.assertGreater(t_zero - t_last, 0.2)
        self.assertLess(t_zero - t_last, 0.32)
        self.assertTrue(all(still(c) for t, c in cmds if t >= t_zero))

    def test_nan_gives_zero(self):
        self.walk()
        t0 = time.monotonic()
        self.send(twist(float("nan")), 0.3)
        self.assert_still_since(t0 + 0.1)

    def test_estop_flag(self):
        self.walk()
        # Published now: left to the 10 Hz thread, up to 0.1 s of the 0.15 s below went by before
        # the flag even left, leaving 50 ms for ROS to deliver it on a loaded machine.
        self.set_estop(True)
        t0 = time.monotonic()
        self.send(twist(0.3), 0.5)
        self.assert_still_since(t0 + 0.15)
        DriverWire.estop_value = False
        self.walk("no motion after the e-stop flag went false")

    def test_stale_high_state_gives_zero_and_error(self):
        self.walk()
        DriverWire.state_on = False
        t0 = time.monotonic()
        self.send(twist(0.3), 1.5)
        self.assert_still_since(t0 + 0.7)
        self.assertEqual(self.fresh_diag().level, DiagnosticStatus.ERROR, "no diagnostics ERROR while stale")
        DriverWire.state_on = True
        self.walk("no motion once the state was fresh again")

    def test_body_pose_force_stand(self):
        call = rospy.ServiceProxy("/set_body_pose", SetBodyPose)
        rospy.wait_for_service("/set_body_pose", timeout=10.0)
        self.assertTrue(call(0.2, -0.3, 0.1, -0.1).success)
        self.assertFalse(call(float("nan"), 0.0, 0.0, 0.0).success)
        self.assertFalse(call(2.0, 0.0, 0.0, 0.0).success)
        want = (0.2, -0.3, 0.1, -0.1)

        def standing_in_pose():
            c = self.last()
            got = tuple(c["euler"]) + (c["bodyHeight"],)
            return c["mode"] == vendor.MODE_FORCE_STAND and all(abs(g - w) < 1e-5 for g, w in zip(got, want))

        self.assertTrue(wait_for(standing_in_pose, 5.0), "no force stand with the pose: %s" % self.last())
        self.assertTrue(call(0.0, 0.0, 0.0, 0.0).success)

    # ---- HighState of both layouts, from the vendor table ----------------------------------------
    def check_odom(self, layout):
        values = dict(
            position=(1.5, -0.5, 0.0),
            velocity=(0.2, 0.05, 0.0),
            yawSpeed=0.3,
            imu={"quaternion": (math.cos(0.25), 0.0, 0.0, math.sin(0.25)), "gyroscope": (0.0, 0.0, 0.3),
                 "accelerometer": (0.1, 0.0, 9.8)},
            footForce=(11, -22, 33, 44),
        )
        if layout == "3.3.4":
            values["motorState"] = [{"q": 0.1 * (i + 1), "dq": -0.01 * i, "tauEst": 0.5 * i} for i in range(20)]
        DriverWire.packet = state_packet(layout, **values)

        def odom_ok():
            odom = rospy.wait_for_message("/rbd_a1_driver/odom", Odometry, timeout=5.0)
            return abs(odom.pose.pose.position.x - 1.5) < 1e-5 and odom
        self.assertTrue(wait_for(odom_ok, 5.0), "odometry never showed the packet's position")
        odom = rospy.wait_for_message("/rbd_a1_driver/odom", Odometry, timeout=5.0)
        imu = rospy.wait_for_message("/rbd_a1_driver/imu", Imu, timeout=5.0)
        self.assertEqual((odom.header.frame_id, odom.child_frame_id), ("odom", "base_link"))
        p, q = odom.pose.pose.position, odom.pose.pose.orientation
        self.assertAlmostEqual(p.x, 1.5, places=5)
        self.assertAlmostEqual(p.y, -0.5, places=5)
        self.assertAlmostEqual(2 * math.atan2(q.z, q.w), 0.5, places=5)
        self.assertAlmostEqual(odom.twist.twist.linear.x, 0.2, places=5)
        self.assertAlmostEqual(odom.twist.twist.linear.y, 0.05, places=5)
        self.assertAlmostEqual(odom.twist.twist.angular.z, 0.3, places=5)
        self.assertAlmostEqual(imu.angular_velocity.z, 0.3, places=5)
        self.assertAlmostEqual(imu.linear_acceleration.z, 9.8, places=5)
        self.assertAlmostEqual(imu.orientation.z, math.sin(0.25), places=5)
        st = self.fresh_diag()
        values = {kv.key: kv.value for kv in st.values}
        self.assertEqual(values["sdk_layout"], layout)
        self.assertEqual(values["sdk_layout_source"], "auto")
        self.assertEqual(values["high_state_size"], str(vendor.HIGH_STATES[layout].size))
        self.assertEqual(values["foot_force"], "[11, -22, 33, 44]")

    def test_334_packets_give_odometry_and_joint_states(self):
        self.check_odom("3.3.4")
        del self.joints[:]
        self.assertTrue(wait_for(lambda: len(self.joints) > 2, 5.0), "no /joint_states from 3.3.4 packets")
        js = self.joints[-1]
        self.assertEqual(list(js.name), list(vendor.JOINT_NAMES))
        for i in range(12):
            self.assertAlmostEqual(js.position[i], 0.1 * (i + 1), places=5)
            self.assertAlmostEqual(js.velocity[i], -0.01 * i, places=5)
            self.assertAlmostEqual(js.effort[i], 0.5 * i, places=5)

    def test_v33_packets_give_odometry_and_no_joint_states(self):
        """v3.3 HighStates (no motorState) give odometry and no /joint_states.

        Joint states of earlier 3.3.4 packets may still be on their way (under load for any time),
        so the boundary is a packet's own stamp: the driver handles packets in order and stamps a
        packet's odometry and joint states alike. The first odometry of a v3.3 packet that no 3.3.4
        packet ever carried (x = 2.5) marks it; no joint state may be stamped at or after it.
        """
        self.check_odom("3.3")
        odoms = []
        sub = rospy.Subscriber("/rbd_a1_driver/odom", Odometry, odoms.append)
        try:
            DriverWire.packet = state_packet("3.3", position=(2.5, -0.5, 0.0))
            marked = wait_for(lambda: [o for o in odoms if abs(o.pose.pose.position.x - 2.5) < 1e-5], 10.0)
            self.assertTrue(marked, "odometry never showed the marked v3.3 packet")
            first = marked[0].header.stamp
            n = len(odoms)
            self.assertTrue(wait_for(lambda: len(odoms) > n + 50, 10.0), "odometry stopped")
        finally:
            sub.unregister()
        late = [j.header.stamp.to_sec() for j in list(self.joints) if j.header.stamp >= first]
        self.assertEqual(late, [], "a v3.3 HighState has no motor states (first v3.3 stamp %.3f)" % first.to_sec())

    def test_unknown_sizes_are_dropped_with_a_clear_error_and_no_motion(self):
        self.walk()
        before = int({kv.key: kv.value for kv in self.fresh_diag().values}["unknown_size_packets"])
        good = state_packet()
        DriverWire.packet = good + b"\x00" * 7  # 1032 B
        t0 = time.monotonic()
        self.send(twist(0.3), 1.2)
        st = self.fresh_diag()
        values = {kv.key: kv.value for kv in st.values}
        self.assertGreater(int(values["unknown_size_packets"]), before + 50, "the odd packets never arrived")
        self.assertEqual(values["high_state_size"], "1032")
        self.assertEqual(st.level, DiagnosticStatus.ERROR)
        for text in ("1032 B", "265 B", "1025 B"):
            self.assertIn(text, st.message)
        self.assert_still_since(t0 + 0.7, "moved on HighStates of an unknown size")
        DriverWire.packet = good
        self.walk("no motion once usable HighStates came again")

    def test_estop_signal_lost_engages_until_fresh_false(self):
        self.walk()
        DriverWire.estop_on = False  # the stand-in controller dies
        t_stop = time.monotonic()
        self.send(twist(0.3), 1.2)
        self.assert_still_since(t_stop + 0.5 + 0.2, "still walking without e-stop signal")
        moving = [t for t, c in self.since(t_stop) if not still(c)]
        self.assertTrue(moving and moving[-1] - t_stop > 0.3, "engaged before the timeout")
        self.assertIn("e-stop signal lost", self.fresh_diag().message)
        DriverWire.estop_on = True  # a fresh false releases
        self.walk("no motion after a fresh false")

    # ---- the A1's remote as a physical e-stop ----------------------------------------------------
    def press(self, held):
        DriverWire.packet = state_packet(wirelessRemote=vendor.remote(["L2", "B"] if held else []))

    def test_remote_estop_engages_at_the_driver_and_only_the_operator_releases(self):
        self.walk()
        del self.remote_held[:]
        t_press, t_press_wall = time.monotonic(), time.time()
        self.press(True)
        self.send(twist(0.3), 0.5)
        self.assertTrue(wait_for(lambda: True in self.remote_held, 30.0), "no remote_estop_held true")
        self.assert_still_since(t_press + 0.05)
        # Measured on the logger's kernel receive times: the HighState carrying the press, then
        # the HighCmds that follow it.
        events = self.events_until(time.time())
        t_packet = press_time(events, t_press_wall)
        after = [(t, vendor.unpack(vendor.HIGH_CMD, d)) for t, ch, d in events if ch == HIGH_CMD and t > t_packet]
        first_zero = next(i for i, (t, c) in enumerate(after) if still(c))
        delay = after[first_zero][0] - t_packet
        rospy.loginfo("MEASURED remote e-stop: zero velocity %.1f ms after the packet (%d HighCmd before it)",
                      delay * 1e3, first_zero)
        self.assertLessEqual(first_zero, 1, "more than the one HighCmd in flight moved after the press")
        self.assertLess(delay, 2.0 / SEND_RATE + 0.005)
        self.assertEqual(self.fresh_diag().level, DiagnosticStatus.WARN)
        self.assertEqual(self.diag_value("remote_estop"), "engaged")
        # Releases while the combination is held are void; so is a plain periodic false.
        self.operator_release()
        t0 = time.monotonic()
        self.send(twist(0.3), 0.5)
        self.assert_still_since(t0, "released while the buttons are held")
        self.press(False)
        self.assertTrue(wait_for(lambda: self.remote_held[-1] is False, 30.0))
        t0 = time.monotonic()
        self.send(twist(0.3), 0.5)
        self.assert_still_since(t0, "released without the operator")
        self.assertEqual(self.fresh_diag().level, DiagnosticStatus.WARN)
        self.operator_release()
        self.assertTrue(wait_for(lambda: self.diag_value("remote_estop") == "ready", 30.0))
        self.walk("no motion after the operator's release")

    # ---- LED, diagnostics, keep-alive -------------------------------------------------------------
    def test_a_stalled_driver_process_is_covered_by_the_keepalive(self):
        """SIGSTOP the driver for 0.4 s while walking: the keep-alive process keeps the HighCmd stream
        going (no gap of 20 ms), repeats the walk for at most keepalive_hold, then zero velocity."""
        self.walk()
        pid = driver_pid()
        t0 = time.time()
        os.kill(pid, signal.SIGSTOP)
        try:
            # Stopped for 0.4 s of a running machine: until the logger holds the reference sender's
            # packets up to then (a stall of the whole machine does not count).
            self.events_until(t0 + 0.4)
        finally:
            os.kill(pid, signal.SIGCONT)
        t1 = time.time()
        self.walk()
        events = self.events_until(t1 + 0.1)
        ref = [t for t, ch, _ in events if ch == REFERENCE]
        window = [(t, vendor.unpack(vendor.HIGH_CMD, d)) for t, ch, d in events
                  if ch == HIGH_CMD and t0 - 0.05 < t < t1 + 0.05]
        stalled = [(t, c) for t, c in window if t0 + 0.02 < t < t1 - 0.02]
        self.assertGreater(len(stalled), 50, "nothing sent while the driver was stopped")
        late = [c for t, c in stalled if t > t0 + KEEPALIVE_HOLD + 0.02]
        self.assertTrue(late and all(still(c) for c in late), "the keep-alive kept the robot walking")
        self.assertEqual(pauses([t for t, _ in window], ref), [])

    def test_a_remote_press_while_the_driver_is_stalled_stops_the_keepalive_fills(self):
        """SIGSTOP the driver while walking, then the A1 reports L2 + B: the keep-alive process, which
        would repeat the walk for keepalive_hold after the driver's last send, fills with zero
        velocity from the HighState with the press on (at most one HighCmd in flight). Without
        the keep-alive's own reading of the remote, the fills inside the hold would walk.

        The press must reach the wire inside the 50 ms hold; when this test's own sender is later
        than that (a loaded machine: 22 ms late in one run), the scene is undone and played again.
        """
        late = []
        for _attempt in range(4):
            self.walk()
            pid = driver_pid()
            t_stop = time.time()
            os.kill(pid, signal.SIGSTOP)
            try:
                self.press(True)  # the test's HighState sender goes on while the driver is stopped
                self.events_until(t_stop + 0.3)  # 0.3 s of a running machine (see the test above)
            finally:
                # Read before the SIGCONT: a packet the driver had made before it stopped (its walk)
                # may reach the wire in the microseconds after the SIGCONT, before a clock read
                # after it; that packet is the driver's, not a fill.
                t_cont = time.time()
                os.kill(pid, signal.SIGCONT)
            self.assertTrue(wait_for(lambda: self.diag_value("remote_estop") == "engaged", 30.0),
                            "the driver never reported the remote e-stop engaged after the stall")
            events = self.events_until(t_cont + 0.1)
            t_packet = press_time(events, t_stop)
            if t_packet < t_stop + KEEPALIVE_HOLD - 0.015:
                break
            late.append(round((t_packet - t_stop) * 1e3, 1))
            self.press(False)
            self.assertTrue(self.release_remote(), "the operator's release did not open the latch")
        else:
            self.fail("the press came too late to be inside the hold in every attempt (ms after the stop: %s)" % late)
        after = [vendor.unpack(vendor.HIGH_CMD, d) for t, ch, d in events if ch == HIGH_CMD and t_packet < t < t_cont]
        trace = " ".join("%.1f:%s" % ((t - t_stop) * 1e3, "%.1f" % vendor.unpack(vendor.HIGH_CMD, d)["velocity"][0]
                                      if ch == HIGH_CMD else "state") for t, ch, d in events
                         if t_stop - 0.01 < t < t_stop + 0.08 and ch != REFERENCE)  # for a failure's message
        inside_hold = [c for t, ch, d in events if ch == HIGH_CMD and t_packet < t < t_stop + KEEPALIVE_HOLD
                       for c in [vendor.unpack(vendor.HIGH_CMD, d)]]
        self.assertGreater(len(after), 40, "the keep-alive did not fill the stall")
        self.assertGreaterEqual(len(inside_hold), 2, "no fill inside the hold after the press")
        moving = [c for c in after if not still(c)]
        self.assertLessEqual(len(moving), 1, "%d fills walked after the press: %s" % (len(moving), trace))
        self.assertTrue(all(still(c) for c in after[len(moving):]),
                        "a fill walked after a fill at rest (after the press): %s" % trace)
        self.press(False)
        self.assertTrue(self.release_remote(), "the operator's release did not open the latch")


    def leds(self):
        return [(led["r"], led["g"], led["b"]) for led in self.last()["led"]]

    def test_led_mirrors_the_gui_state_colour(self):
        for status, rgb in (("running", (0x2E, 0x7D, 0x32)), ("collision", (0xEF, 0x6C, 0x00)),
                            ("idle", (0x15, 0x65, 0xC0))):
            self.status.publish(String(status))
            self.assertTrue(wait_for(lambda rgb=rgb: self.leds() == [rgb] * 4, 30.0), "%s: %s" % (status, self.leds()))
        DriverWire.estop_value = True
        self.assertTrue(wait_for(lambda: self.leds() == [(0xC6, 0x28, 0x28)] * 4, 30.0), "e-stop is not red")

    def test_diagnostics_contract(self):
        # The second diagnostics from now: the first may have been made before setUp put back the
        # nominal HighState (an earlier test's foot forces / SDK 3.3 packet) and arrived after it.
        n = len(self.diag)
        self.assertTrue(wait_for(lambda: len(self.diag) >= n + 2, 5.0), "no two more /diagnostics")
        st = self.diag[n + 1].status[0]
        self.assertEqual(st.name, "rbd_a1_driver: A1 link")
        v = {kv.key: kv.value for kv in st.values}
        for key in ("sdk_layout", "sdk_layout_source", "high_state_size", "high_state_rate", "high_cmd_rate",
                    "unknown_size_packets", "estop_gate_armed", "remote_estop", "foot_force"):
            self.assertIn(key, v)
        self.assertEqual(v["sdk_layout"], "3.3.4")
        self.assertEqual(v["estop_gate_armed"], "true")
        self.assertEqual(v["remote_estop"], "ready")
        self.assertEqual(v["foot_force"], "[29, 30, 31, 32]")
        # The rates against lcm-logger's record of the same interval (kernel receive times), not
        # against fixed numbers: on a loaded 2-core machine a driver that sends 150 packets a
        # second must say 150. The keep-alive process fills the driver's gaps on the wire and
        # the driver counts only its own packets, so the wire may hold more HighCmd than it reports.
        first, second = self.diag[n], self.diag[n + 1]
        t0, t1 = first.header.stamp.to_sec(), second.header.stamp.to_sec()
        events = self.events_until(t1)
        v = {kv.key: kv.value for kv in second.status[0].values}
        wire = {ch: sum(1 for t, c, _ in events if c == ch and t0 < t <= t1) / (t1 - t0)
                for ch in (HIGH_CMD, HIGH_STATE)}
        cmd, state = float(v["high_cmd_rate"]), float(v["high_state_rate"])
        rospy.loginfo("MEASURED diagnostics rates: HighCmd %.1f/s reported, %.1f/s on the wire; HighState %.1f/s "
                      "reported, %.1f/s on the wire", cmd, wire[HIGH_CMD], state, wire[HIGH_STATE])
        self.assertGreater(wire[HIGH_STATE], 50.0)  # the fake server's 200 Hz stream flows
        self.assertLess(abs(state - wire[HIGH_STATE]), 0.25 * wire[HIGH_STATE] + 10.0, (state, wire))
        self.assertTrue(50.0 < cmd <= 1.1 * wire[HIGH_CMD] + 10.0, (cmd, wire))
        self.assertLessEqual(cmd, 260.0)  # the driver's 250 Hz, never more

    def test_keepalive_from_the_first_second_with_no_gap_over_20ms(self):
        """The HighCmd stream on record from the driver's first packet on, through e-stop engage and
        release, the remote e-stop and a stale state: never a gap of 20 ms (lcm_server_high's limit)."""
        self.walk()
        DriverWire.estop_value = True
        self.send(twist(0.3), 0.5)
        DriverWire.estop_value = False
        self.walk()
        self.press(True)
        self.send(twist(0.3), 0.3)
        self.press(False)
        self.assertTrue(self.release_remote())
        DriverWire.state_on = False
        self.send(twist(0.3), 1.0)
        DriverWire.state_on = True
        self.walk()
        t_end = time.time()
        events = self.events_until(t_end)
        cmds = [t for t, ch, _ in events if ch == HIGH_CMD]
        ref = [t for t, ch, _ in events if ch == REFERENCE]
        gaps = [(b - a, a, b) for a, b in zip(cmds, cmds[1:])]
        first = cmds[0] - self.driver_registered
        over = [g for g in gaps if g[0] >= KEEPALIVE_GAP]
        driver_pauses = pauses(cmds, ref)
        rospy.loginfo("MEASURED keep-alive: %d HighCmd over %.1f s, largest gap %.1f ms; %d gaps >= 20 ms, %d of them "
                      "while the machine ran (the reference sender was not silent); first HighCmd %.3f s after the "
                      "driver registered, %.3f s after its process started", len(cmds), cmds[-1] - cmds[0],
                      max(gaps)[0] * 1e3, len(over), len(driver_pauses), first, cmds[0] - self.driver_started)
        self.assertLess(first, 1.0, "the driver did not send within its first second")
        # On record to the end of the scene above (this test may run first, on a fast machine the
        # whole record is then ~3 s long): the last HighCmd within a few send periods of its end.
        self.assertGreater(cmds[-1], t_end - 0.05, "the record ends %.3f s before the scene" % (t_end - cmds[-1]))
        self.assertGreater(len(ref), 1000, "the reference sender did not run")
        self.assertEqual(driver_pauses, [], "the HighCmd stream paused >= 20 ms while the machine ran "
                                            "(lcm_server_high would exit)")


def driver_pid():
    """PID of the running driver node (its XML-RPC getPid)."""
    api = rosnode.get_api_uri(rosgraph.Master("/driver_wire"), "/rbd_a1_driver", skip_cache=True)
    code, _msg, pid = xmlrpc.client.ServerProxy(api).getPid("/driver_wire")
    assert code == 1, _msg
    return pid


def pauses(cmds, ref):
    """Gaps >= 20 ms between HighCmd times that the machine does not explain (reference sender active)."""
    return [(b - a, a, b) for a, b in zip(cmds, cmds[1:])
            if b - a >= KEEPALIVE_GAP and not machine_stalled(ref, a, b)]


def machine_stalled(ref, a, b, slack=0.010):
    """True if the reference sender was silent for all but ``slack`` of the interval (a, b)."""
    for ra, rb in zip(ref, ref[1:]):
        if rb <= a or ra >= b:
            continue
        if min(b, rb) - max(a, ra) >= (b - a) - slack:
            return True
    return False


if __name__ == "__main__":
    run_rostest(PKG, "driver_wire", DriverWire)
