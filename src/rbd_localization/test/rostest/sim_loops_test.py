#!/usr/bin/env python3
"""Loops (1, or RBD_LOC_SIM_LOOPS) of the thesis path in the seeded simulator: the corrected pose ends on the truth.

The robot is steered on ground truth by sim_loops.py; the checks compare, at every loop end,
/rbd_localization/pose with /rbd_sim/ground_truth (thresholds of the issue: 0.05 m, 1 deg).
"""

import os
import sys
import unittest

import rospy

from rbd_testkit.ros import run_rostest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sim_loops  # noqa: E402

LOOPS = int(os.environ.get("RBD_LOC_SIM_LOOPS", "1"))


class SimLoopsTest(unittest.TestCase):
    """Drive, then check what was recorded."""

    @classmethod
    def setUpClass(cls):
        rospy.init_node("sim_loops_test")
        cls.report = sim_loops.run(LOOPS)

    def test_corrected_pose_on_truth_at_every_loop_end(self):
        loops = self.report["loops"]
        self.assertEqual(len(loops), LOOPS)
        for e in loops:
            rospy.loginfo("loop %d corrected %s ekf-only %s", e["loop"], e["corrected"], e["ekf"])
            self.assertIsNotNone(e["corrected"])
            self.assertLess(e["corrected"]["pos_err"], 0.05, e)
            self.assertLess(e["corrected"]["yaw_err_deg"], 1.0, e)

    def test_robot_really_drove_the_path(self):
        xs = [p[0] for p in self.report["tracks"]["truth"]]
        self.assertGreater(max(xs), 0.9)
        self.assertLess(min(xs), -0.9)


if __name__ == "__main__":
    run_rostest("rbd_localization", "sim_loops", SimLoopsTest)
