#!/usr/bin/env python3
"""Loops (1, or RBD_LOC_SIM_LOOPS) of the thesis path in the seeded simulator: the corrected pose ends on the truth.

The robot is steered on ground truth by sim_loops.py; the checks compare, at every loop end,
/rbd_localization/pose with /rbd_sim/ground_truth (thresholds of the issue: 0.05 m, 1 deg).
"""

import json
import os
import sys
import unittest

import rospy

from rbd_testkit.ros import run_rostest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sim_loops  # noqa: E402

LOOPS = int(os.environ.get("RBD_LOC_SIM_LOOPS", "1"))
# m over the whole run: the EKF alone follows the simulated ZED2's drift (3 % of the distance) and
# its jumps (0.05-0.3 m); measured 0.26 m, RoboDog's EKF alone 0.16-0.24 m in the same runs; a
# filter that did not follow the robot would be ~1 m off at the far end of the path.
RL_STYLE_MAX_ERR = 0.4


class SimLoopsTest(unittest.TestCase):
    """Drive, then check what was recorded."""

    @classmethod
    def setUpClass(cls):
        rospy.init_node("sim_loops_test")
        cls.report = sim_loops.run(LOOPS, extra_odometry={"rl_style": "/rl_style/odometry/filtered",
                                                          "ekf": "/odometry/filtered"})
        if os.environ.get("RBD_LOC_SIM_REPORT"):  # the whole report, for a look by hand
            with open(os.environ["RBD_LOC_SIM_REPORT"], "w") as f:
                json.dump(cls.report, f)

    def test_corrected_pose_on_truth_at_every_loop_end(self):
        loops = self.report["loops"]
        self.assertEqual(len(loops), LOOPS)
        for e in loops:
            rospy.loginfo("loop %d corrected %s ekf-only %s", e["loop"], e["corrected"], e["ekf"])
            self.assertIsNotNone(e["corrected"])
            self.assertLess(e["corrected"]["pos_err"], 0.05, e)
            self.assertLess(e["corrected"]["yaw_err_deg"], 1.0, e)

    def test_rl_style_configuration_tracks_the_truth(self):
        # test/config/rl_style_sim.yaml: an r_l file as written (`1e-9` text entries), no RoboDog
        # extensions, EKF alone (no map correction): it follows the robot round the loop.
        e = self.report["extra"]["rl_style"]
        for name, x in sorted(self.report["extra"].items()):
            rospy.loginfo("%s: max %.3f m, final %s m, %d samples", name, x["max_err"], x["final_err"], x["samples"])
        self.assertGreater(e["samples"], 100)
        xs = [p[0] for p in e["track"]]
        self.assertGreater(max(xs), 0.8)
        self.assertLess(min(xs), -0.8)
        self.assertLess(e["max_err"], RL_STYLE_MAX_ERR)

    def test_robot_really_drove_the_path(self):
        xs = [p[0] for p in self.report["tracks"]["truth"]]
        self.assertGreater(max(xs), 0.9)
        self.assertLess(min(xs), -0.9)


if __name__ == "__main__":
    run_rostest("rbd_localization", "sim_loops", SimLoopsTest)
