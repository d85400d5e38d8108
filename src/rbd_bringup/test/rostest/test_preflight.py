#!/usr/bin/env python3
"""rostest: `preflight` on the simulated system (SDK v3.3), then one injected fault at a time.

Each fault must make exactly its own line FAIL, with a message that names the cause; the lines
that cannot be judged without the failed input say SKIP (the expected ones are listed here, per
fault); every other line passes. Before each fault the test proves its input reached the graph
(the relay stopped/changed, the driver counted the odd packets, the second publisher is on
/tf_static, ...).

The faults are injected from outside the preflight code: the OS1's cloud and the ZED2 pose
reach their real topics through relays in this test (preflight.test remaps the simulator's
publishers); a second LCM publisher sends HighState packets of a size no SDK has; a fake "other
host" answers XML-RPC with a skewed HTTP Date; robot_state_publisher is replaced by one with an
edited URDF (no os_sensor, or the OS1 mounted 0.10 m higher than the simulated one really is);
a second publisher gives zed2_camera_center another parent, as zed-ros-wrapper's publish_urdf does.
"""

import contextlib
import copy
import functools
import http.server
import json
import os
import signal
import socketserver
import subprocess
import threading
import time
import traceback
import unittest
import xml.etree.ElementTree as ET
import xmlrpc.client

import lcm
import rosgraph
import rospy
import tf2_ros
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped, TransformStamped
from sensor_msgs.msg import PointCloud2, PointField

import rbd_preflight as preflight
import rbd_testkit
from rbd_msgs.msg import CollisionState
from rbd_preflight import collect
from rbd_testkit.ros import run_rostest

RAW_POINTS = "/preflight_test/sim_points"
RAW_ZED2 = "/preflight_test/sim_zed2"
DURATION = 2.5  # observation per run [s]
FAKE_HOST = "127.0.0.2"


# The kit's wait_for, ending early when ROS shuts down.
wait_for = functools.partial(rbd_testkit.wait_for, abort=rospy.is_shutdown)


class Relays:
    """The OS1 cloud and the ZED2 pose pass through here: pass, silent, or (cloud) another layout."""

    def __init__(self):
        self.cloud_mode = "pass"
        self.zed2_mode = "pass"
        self.sent = {"cloud": 0, "zed2": 0, "odd_cloud": 0}
        self.held = {"cloud": 0, "zed2": 0}  # arrived from the simulator while silent: the input goes on
        self.cloud_pub = rospy.Publisher("/ouster/points", PointCloud2, queue_size=2)
        self.zed2_pub = rospy.Publisher("/zed2/zed_node/pose_with_covariance", PoseWithCovarianceStamped,
                                        queue_size=10)
        rospy.Subscriber(RAW_POINTS, PointCloud2, self.on_cloud, queue_size=2, buff_size=1 << 25)
        rospy.Subscriber(RAW_ZED2, PoseWithCovarianceStamped, self.on_zed2, queue_size=10)

    def on_cloud(self, msg):
        if self.cloud_mode == "pass":
            self.cloud_pub.publish(msg)
            self.sent["cloud"] += 1
        elif self.cloud_mode == "xyzi":
            self.cloud_pub.publish(xyzi_layout(msg))
            self.sent["odd_cloud"] += 1
        else:
            self.held["cloud"] += 1

    def on_zed2(self, msg):
        if self.zed2_mode == "pass":
            self.zed2_pub.publish(msg)
            self.sent["zed2"] += 1
        else:
            self.held["zed2"] += 1


def xyzi_layout(msg):
    """The same points with only x, y, z, intensity declared (a PCL PointXYZI-style cloud, no range)."""
    odd = copy.copy(msg)
    odd.fields = [PointField(name=n, offset=o, datatype=PointField.FLOAT32, count=1)
                  for n, o in (("x", 0), ("y", 4), ("z", 8), ("intensity", 16))]
    return odd


class FakeRemoteHost:
    """Another "host" of the graph: an XML-RPC server on 127.0.0.2 whose HTTP Date runs ``skew`` s ahead."""

    def __init__(self):
        self.skew = 0.0
        outer = self

        class Handler(http.server.BaseHTTPRequestHandler):
            def date_time_string(self, timestamp=None):
                return http.server.BaseHTTPRequestHandler.date_time_string(self, time.time() + outer.skew)

            def do_POST(self):  # noqa: N802 (http.server's name)
                self.rfile.read(int(self.headers.get("Content-Length", 0)))
                body = xmlrpc.client.dumps(((1, "", os.getpid()),), methodresponse=True).encode()
                self.send_response(200)
                self.send_header("Content-Type", "text/xml")
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)

            def log_message(self, *args):
                pass

        class Server(socketserver.ThreadingMixIn, http.server.HTTPServer):
            daemon_threads = True

        self.server = Server((FAKE_HOST, 0), Handler)
        threading.Thread(target=self.server.serve_forever, daemon=True).start()
        self.uri = "http://%s:%d/" % (FAKE_HOST, self.server.server_address[1])
        self.master = rosgraph.Master("/preflight_fake_remote")
        self.master.registerPublisher("/preflight_test/remote_host", "std_msgs/String", self.uri)

    def close(self):
        try:
            self.master.unregisterPublisher("/preflight_test/remote_host", self.uri)
        except Exception:
            pass
        self.server.shutdown()


def node_pid(name):
    uri = rosgraph.Master("/test_preflight").lookupNode(name)
    code, _msg, pid = xmlrpc.client.ServerProxy(uri).getPid("/test_preflight")
    assert code == 1
    return int(pid)


class Preflight(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_preflight")
        cls.relays = Relays()
        cls.remote = FakeRemoteHost()
        cls.rsp = None
        cls.zone = []
        cls.pose = []
        cls.diag = []
        rospy.Subscriber("/rbd_lidar/state", CollisionState, lambda m: cls.zone.append((time.monotonic(), m)))
        rospy.Subscriber("/rbd_localization/pose", PoseStamped, lambda m: cls.pose.append(time.monotonic()))
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.on_diag)
        cls.description = None

    @classmethod
    def on_diag(cls, msg):
        for st in msg.status:
            if st.name == preflight.A1_DIAG_NAME:
                cls.diag.append({kv.key: kv.value for kv in st.values})

    @classmethod
    def tearDownClass(cls):
        cls.remote.close()
        if cls.rsp is not None:
            os.killpg(cls.rsp.pid, signal.SIGINT)
            cls.rsp.wait(15)

    # ----------------------------------------------------------------------------- helpers
    @contextlib.contextmanager
    def case(self, name):
        """A subTest whose failure is also logged (rosunit's XML report drops subTest messages)."""
        with self.subTest(name):
            try:
                yield
            except Exception:
                rospy.logerr("case %r failed:\n%s", name, traceback.format_exc())
                raise

    def settle(self, timeout=60.0):
        """The inputs flow again: a fresh, clean zone state, a fresh pose, clouds and ZED2 poses relayed."""
        def fresh():
            now = time.monotonic()
            zone_ok = self.zone and now - self.zone[-1][0] < 0.3 and not self.zone[-1][1].stale \
                and not self.zone[-1][1].error
            return zone_ok and self.pose and now - self.pose[-1] < 0.2
        sent = dict(self.relays.sent)
        self.assertTrue(wait_for(lambda: self.relays.sent["cloud"] > sent["cloud"] + 3
                                 and self.relays.sent["zed2"] > sent["zed2"] + 5, timeout), "relays not passing")
        self.assertTrue(wait_for(fresh, timeout), "zone / localization not fresh again")

    def preflight(self):
        rows, _obs = collect.run(DURATION)
        table = preflight.render(rows)
        rospy.loginfo("preflight:\n%s", table)
        return rows, table

    def assert_only(self, rows, table, key, texts=(), skipped=()):
        """Exactly ``key`` FAILs (its value naming ``texts``), ``skipped`` say SKIP, the rest PASS."""
        by_key = {r.key: r for r in rows}
        self.assertEqual([r.key for r in rows if r.status == preflight.FAIL], [key], table)
        self.assertEqual(sorted(r.key for r in rows if r.status == preflight.SKIP), sorted(skipped), table)
        failed = by_key[key]
        self.assertTrue(failed.hint, "no 'what to do' on the failing line:\n" + table)
        for text in texts:
            self.assertIn(text, failed.value, table)
        return failed

    def replace_rsp(self, edit):
        """robot_state_publisher with this test's copy of the URDF, edited by ``edit(root)``."""
        if self.description is None:
            type(self).description = rospy.get_param("/robot_description")
            pid = node_pid("/robot_state_publisher")
            os.kill(pid, signal.SIGINT)
            master = rosgraph.Master("/test_preflight")

            def gone():
                try:
                    master.lookupNode("/robot_state_publisher")
                    return False
                except rosgraph.MasterError:
                    return True
            self.assertTrue(wait_for(gone, 20.0), "robot_state_publisher did not stop")
        if self.rsp is not None:
            os.killpg(self.rsp.pid, signal.SIGINT)
            self.rsp.wait(15)
        root = ET.fromstring(self.description)
        edit(root)
        rospy.set_param("/preflight_test/robot_description", ET.tostring(root, encoding="unicode"))
        type(self).rsp = subprocess.Popen(
            ["rosrun", "robot_state_publisher", "robot_state_publisher", "__name:=rsp_test", "__ns:=/preflight_test",
             "joint_states:=/joint_states", "_publish_frequency:=30.0"], start_new_session=True)
        master = rosgraph.Master("/test_preflight")
        self.assertTrue(wait_for(lambda: any(
            t == "/tf_static" and "/preflight_test/rsp_test" in nodes for t, nodes in master.getSystemState()[0]),
            30.0), "the test's robot_state_publisher did not come up")

    # ----------------------------------------------------------------------------- the test
    def test_preflight_and_faults(self):
        self.settle(120.0)
        self.assertTrue(wait_for(lambda: self.diag and self.diag[-1].get("estop_gate_armed") == "true", 30.0))

        # The command itself on the healthy system: every line passes, exit 0; both hosts' clocks read.
        proc = subprocess.run(["rosrun", "rbd_preflight", "preflight", "--json", "--duration", str(DURATION)],  # noqa: UP022
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True, timeout=120)
        report = json.loads(proc.stdout)
        table = "\n".join("%(status)s %(name)s %(value)s %(hint)s" % r for r in report["rows"])
        self.assertEqual([r["key"] for r in report["rows"] if r["status"] != "PASS"], [], table)
        self.assertEqual(proc.returncode, 0, table)
        rows = {r["key"]: r for r in report["rows"]}
        self.assertIn("SDK 3.3,", rows["a1_layout"]["value"])  # this rostest runs the v3.3 layout
        self.assertIn(FAKE_HOST, rows["clocks"]["value"])  # the "other host" was measured, in sync
        self.assertIn("no clients connected", rows["bridge"]["value"])
        # no map loaded: the map correction's own diagnostics say mapping mode (issue 29)
        self.assertIn("n/a: no map loaded (map correction in mapping mode", rows["localized"]["value"])
        self.assertEqual(report["mounts"]["os_sensor"], "xyz (-0.080, 0.000, 0.070) m, rpy (0.0, 0.0, 0.0) deg")

        with self.case("LiDAR silent"):
            self.relays.cloud_mode = "silent"
            held = self.relays.held["cloud"]
            # the simulator goes on sending and the relay holds it back (no callback mid-publish)
            self.assertTrue(wait_for(lambda: self.relays.held["cloud"] > held + 1, 10.0), "simulated OS1 silent")
            n = self.relays.sent["cloud"]
            rows, table = self.preflight()
            self.assertEqual(self.relays.sent["cloud"], n)
            self.assert_only(rows, table, "lidar_cloud", ["nothing in"], ["lidar_layout", "zone", "floor"])
            self.relays.cloud_mode = "pass"
            self.settle()

        with self.case("wrong cloud layout"):
            self.relays.cloud_mode = "xyzi"
            odd = self.relays.sent["odd_cloud"]
            self.assertTrue(wait_for(lambda: self.relays.sent["odd_cloud"] > odd + 1, 10.0))
            rows, table = self.preflight()
            self.assert_only(rows, table, "lidar_layout", ["no field range", "no field ring"], ["zone", "floor"])
            self.relays.cloud_mode = "pass"
            self.settle()

        with self.case("ZED2 silent"):
            self.relays.zed2_mode = "silent"
            held = self.relays.held["zed2"]
            self.assertTrue(wait_for(lambda: self.relays.held["zed2"] > held + 1, 10.0), "simulated ZED2 silent")
            n = self.relays.sent["zed2"]
            rows, table = self.preflight()
            self.assertEqual(self.relays.sent["zed2"], n)
            self.assert_only(rows, table, "zed2", ["nothing in"])
            self.relays.zed2_mode = "pass"
            self.settle()

        with self.case("HighState of an unknown size"):
            lc = lcm.LCM(rospy.get_param("/rbd_sim/lcm_url"))
            stop = threading.Event()

            def odd_sender():
                while not stop.is_set():
                    lc.publish("LCM_High_State", bytes(300))
                    time.sleep(0.01)
            sender = threading.Thread(target=odd_sender, daemon=True)
            counted = int(self.diag[-1]["unknown_size_packets"])
            sender.start()
            try:
                self.assertTrue(wait_for(lambda: int(self.diag[-1]["unknown_size_packets"]) > counted, 10.0),
                                "the driver never saw the 300 B packets")
                rows, table = self.preflight()
            finally:
                stop.set()
                sender.join()
            self.assert_only(rows, table, "a1_layout", ["300 B (unknown)"])

        with self.case("clocks of two hosts 200 ms apart"):
            self.remote.skew = 0.2
            rows, table = self.preflight()
            self.remote.skew = 0.0
            failed = self.assert_only(rows, table, "clocks", [FAKE_HOST])
            self.assertRegex(failed.value, r"127\.0\.0\.2 \+(19\d|20\d)\.\d")

        with self.case("a TF frame with two parents"):
            broadcaster = tf2_ros.StaticTransformBroadcaster()
            edges = []
            for parent, child, z in (("base_link", "zed2_base_link", 0.05), ("zed2_base_link", "zed2_camera_center",
                                                                             0.01)):
                t = TransformStamped()
                t.header.stamp = rospy.Time.now()
                t.header.frame_id, t.child_frame_id = parent, child
                t.transform.translation.x, t.transform.translation.z = 0.22, z
                t.transform.rotation.w = 1.0
                edges.append(t)
            broadcaster.sendTransform(edges)
            rows, table = self.preflight()
            broadcaster.pub_tf.unregister()
            failed = self.assert_only(rows, table, "tf_parents", ["zed2_camera_center has 2 parents"])
            self.assertIn(rospy.get_name(), failed.value)  # the second publisher is named
            self.assertIn("/robot_state_publisher", failed.value)

        with self.case("TF base_link -> os_sensor missing"):
            def drop_os_sensor(root):
                for joint in root.findall("joint"):
                    if joint.find("child").get("link") == "os_sensor":
                        root.remove(joint)
                root.remove([link for link in root.findall("link") if link.get("name") == "os_sensor"][0])
            self.replace_rsp(drop_os_sensor)
            rows, table = self.preflight()
            self.assert_only(rows, table, "tf_lidar", ["base_link -> os_sensor missing"], ["zone", "floor"])

        with self.case("LiDAR mounted 0.10 m lower than the mounts file says"):
            def raise_os_sensor(root):
                for joint in root.findall("joint"):
                    if joint.find("child").get("link") == "os_sensor":
                        origin = joint.find("origin")
                        x, y, z = (float(v) for v in origin.get("xyz").split())
                        origin.set("xyz", "%r %r %r" % (x, y, z + 0.10))
            self.replace_rsp(raise_os_sensor)
            rows, table = self.preflight()
            failed = self.assert_only(rows, table, "floor", ["from the expected one"])
            self.assertRegex(failed.value, r"floor \+0\.(09|10|11)\d m")
            self.assertIn("too high", failed.hint)
            tf_row = [r for r in rows if r.key == "tf_lidar"][0]
            self.assertIn("xyz (-0.080, 0.000, 0.170)", tf_row.value)


if __name__ == "__main__":
    run_rostest("rbd_bringup", "preflight_test", Preflight)
