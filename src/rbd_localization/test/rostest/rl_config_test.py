#!/usr/bin/env python3
"""robot_localization's configuration files as written, through the real rosparam path.

ekf_synthetic.test starts ekf_localization_node twice with r_l-style files (test/config/): the
template loaded with <rosparam command="load"> (as r_l's launch/ekf_template.launch does) and the
launch-file forms of r_l's test launch files (<param>, inline <rosparam>). The oracle is the text
of those files: the numbers written there, read as r_l reads them (every matrix entry through a
string stream, 225 entries row-major; 15 entries are RoboDog's diagonal form). The filter's
matrices and options are read back from its latched ~effective_config (built from the Ekf's own
matrices). A third start, with a 224-number matrix, must stop with an error naming it before it
publishes anything.
"""

import json
import os
import subprocess
import time
import unittest

import rospy
from nav_msgs.msg import Odometry
from std_msgs.msg import String

from rbd_testkit import wait_for
from rbd_testkit.ros import run_rostest

PKG_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CONFIG_DIR = os.path.join(PKG_DIR, "test", "config")
NO_GATE = 1.7976931348623157e308  # r_l's default threshold: numeric_limits<double>::max()
# params/ekf_template.yaml's process noise diagonal, as written in test/config/rl_template.yaml.
TEMPLATE_Q = [0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015]


def diagonal(values):
    """Return the 225 row-major entries of the diagonal matrix with these 15 values."""
    return [values[r] if r == c else 0.0 for r in range(15) for c in range(15)]


def config(ones):
    """Return 15 booleans from a string such as '000111000111111'."""
    return [c == "1" for c in ones]


def wait_latched(topic, timeout=30.0):
    """Return the parsed JSON of the first (latched) message on a std_msgs/String topic."""
    got = []
    sub = rospy.Subscriber(topic, String, lambda msg: got.append(msg.data))
    try:
        wait_for(lambda: got, timeout, what="a message on %s" % topic)
    finally:
        sub.unregister()
    return json.loads(got[0])


class RlConfigTest(unittest.TestCase):
    """Checks what the filters took from the files."""

    @classmethod
    def setUpClass(cls):
        rospy.init_node("rl_config_test")
        cls.template = wait_latched("/template/ekf/effective_config")
        cls.forms = wait_latched("/launch_forms/ekf/effective_config")

    def sensor(self, cfg, name):
        for s in cfg["sensors"]:
            if s["name"] == name:
                return s
        self.fail("%s not configured: %s" % (name, [s["name"] for s in cfg["sensors"]]))

    def assert_matrix(self, got, expected):
        """Compare 225 entries, each within 1e-12 relative."""
        self.assertEqual(len(got), 225)
        for i, (g, e) in enumerate(zip(got, expected)):
            self.assertAlmostEqual(g, e, delta=abs(e) * 1e-12, msg="entry %d (row %d, col %d)" % (i, i // 15, i % 15))

    def test_rosparam_delivered_yaml_1_1_types(self):
        # The premise: through rosparam, `1e-9` is text and `0` an integer (so the string path is
        # what the filter below was really fed); roslaunch's <param value="1e-1"> is text too.
        p0 = rospy.get_param("/template/ekf/initial_estimate_covariance")
        self.assertEqual(p0[0], "1e-9")
        self.assertIsInstance(p0[1], int)
        self.assertIsInstance(rospy.get_param("/template/ekf/process_noise_covariance")[0], float)
        self.assertIsInstance(rospy.get_param("/template/ekf/odom0_pose_rejection_threshold"), int)
        self.assertEqual(rospy.get_param("/launch_forms/ekf/process_noise_covariance")[0], "1e-3")
        self.assertEqual(rospy.get_param("/launch_forms/ekf/initial_estimate_covariance")[5], "1e-3")
        self.assertEqual(rospy.get_param("/launch_forms/ekf/sensor_timeout"), "1e-1")
        self.assertIsInstance(rospy.get_param("/launch_forms/ekf/frequency"), int)

    def test_template_matrices(self):
        self.assert_matrix(self.template["process_noise_covariance"], diagonal(TEMPLATE_Q))
        self.assert_matrix(self.template["initial_estimate_covariance"], diagonal([1e-9] * 15))

    def test_template_options(self):
        t = self.template
        self.assertEqual((t["frequency"], t["sensor_timeout"], t["two_d_mode"], t["publish_tf"]),
                         (30, 0.1, False, False))
        self.assertEqual((t["world_frame"], t["base_link_frame"], t["debug_out_file"]),
                         ("odom", "base_link", "/path/to/debug/file.txt"))
        self.assertEqual(sorted(s["name"] for s in t["sensors"]), ["imu0", "odom0", "odom1", "pose0", "twist0"])
        odom0 = self.sensor(t, "odom0")
        self.assertEqual(odom0["topic"], "example/odom")
        self.assertEqual(odom0["config"], config("110000000001000"))
        self.assertEqual((odom0["queue_size"], odom0["pose_rejection_threshold"], odom0["twist_rejection_threshold"]),
                         (2, 5.0, 1.0))
        odom1 = self.sensor(t, "odom1")
        self.assertEqual((odom1["relative"], odom1["differential"], odom1["twist_rejection_threshold"]),
                         (True, False, 0.2))
        pose0 = self.sensor(t, "pose0")
        self.assertEqual((pose0["differential"], pose0["queue_size"], pose0["pose_rejection_threshold"]),
                         (True, 5, 2.0))
        twist0 = self.sensor(t, "twist0")
        self.assertEqual((twist0["config"], twist0["queue_size"], twist0["twist_rejection_threshold"]),
                         (config("000000111000000"), 3, 2.0))
        imu0 = self.sensor(t, "imu0")
        self.assertEqual(imu0["config"], config("000111000111111"))
        self.assertEqual((imu0["relative"], imu0["differential"], imu0["remove_gravitational_acceleration"]),
                         (True, False, True))
        self.assertEqual((imu0["pose_rejection_threshold"], imu0["twist_rejection_threshold"],
                          imu0["linear_acceleration_rejection_threshold"], imu0["queue_size"]), (0.8, 0.8, 0.8, 5))
        # The one option of the template this node lacks is named; nothing is "unknown".
        self.assertEqual(len(t["warnings"]), 1, t["warnings"])
        self.assertIn("use_control", t["warnings"][0])

    def test_launch_file_forms(self):
        f = self.forms
        self.assertEqual(f["frequency"], 50)  # <param value="50"> over the file's 30
        # <param value="1e-1"> arrives as text: read as 0.1 and said so (r_l would keep its default).
        self.assertEqual(f["sensor_timeout"], 0.1)
        self.assertEqual(len([w for w in f["warnings"] if w.startswith("sensor_timeout")]), 1, f["warnings"])
        self.assert_matrix(f["process_noise_covariance"],
                          diagonal([1e-3, 1e-3, 1e-3, 3e-2, 3e-2, 6e-2, 2.5e-2, 2.5e-2, 4e-2, 1e-2, 1e-2, 2e-2,
                                    1e-2, 1e-2, 1.5e-2]))
        self.assert_matrix(f["initial_estimate_covariance"],
                          diagonal([1e-6, 1e-6, 1e-9, 1e-9, 1e-9, 1e-3] + [1e-9] * 9))
        self.assertEqual([s["name"] for s in f["sensors"]], ["imu0"])
        imu0 = f["sensors"][0]
        self.assertEqual((imu0["queue_size"], imu0["twist_rejection_threshold"], imu0["pose_rejection_threshold"]),
                         (10, 8.0, NO_GATE))
        unknown = [w for w in f["warnings"] if w.startswith("unknown parameters")]
        self.assertEqual(len(unknown), 1, f["warnings"])
        for key in ("frequncy", "imu2", "imu2_config"):
            self.assertIn(key, unknown[0])
        self.assertIn("without gaps", unknown[0])

    def test_bad_value_stops_the_node_before_it_publishes(self):
        received = []
        subs = [rospy.Subscriber("/bad/odometry/filtered", Odometry, received.append),
                rospy.Subscriber("/bad/ekf/effective_config", String, received.append)]
        subprocess.run(["rosparam", "load", os.path.join(CONFIG_DIR, "rl_bad.yaml"), "/bad/ekf"], check=True)
        start = time.time()
        proc = subprocess.run(  # noqa: UP022 (Python 3.6 has no capture_output)
            ["rosrun", "rbd_localization", "ekf_localization_node", "__name:=ekf", "__ns:=/bad"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True, timeout=30)
        output = proc.stdout + proc.stderr
        # It ran and read the file: the error names the parameter and what is wrong with it.
        self.assertIn("initial_estimate_covariance", output)
        self.assertIn("got 224", output)
        self.assertEqual(proc.returncode, 1, output)
        self.assertLess(time.time() - start, 20.0)
        # The node is gone: what it sent before it exited came before its connections' end, and
        # rospy hands a connection's messages to the callback before it drops the connection.
        wait_for(lambda: not any(s.impl.connections for s in subs), 5.0, what="the bad node's connections closed")
        for s in subs:
            s.unregister()
        self.assertEqual(received, [])


if __name__ == "__main__":
    run_rostest("rbd_localization", "rl_config", RlConfigTest)
