"""The fault catalogue's repeated rounds (`make test-long`; README "Tests").

`make test` runs every fault of ``faults_nodes.test`` and ``faults_inputs.test`` once (one round,
each from a walking robot). These run the same rostests with the rounds they had before
(2 and 3): the same fault injected again on the same stack, after its recovery, must stop and
recover the robot again. Reason for the move: the extra rounds were about 100 s of the serial
lane (CI, 2026-11-28), the lane that bounds `make test`'s wall time.
"""

import collections
import json
import os
import re
import subprocess

import pytest

pytestmark = pytest.mark.long

ROSTEST_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                           "src", "rbd_bringup", "test", "rostest")


def every_round_faults(test_file):
    """The faults of the .test file's default list that run in every round (no ``NAME:N``)."""
    with open(os.path.join(ROSTEST_DIR, test_file)) as f:
        spec = re.search(r'<arg name="faults" default="([^"]*)"', f.read()).group(1)
    return [name for name in spec.split() if ":" not in name]


@pytest.mark.timeout(1500)
@pytest.mark.parametrize("test_file, rounds", [("faults_nodes.test", 2), ("faults_inputs.test", 3)])
def test_every_fault_again_on_the_same_stack(test_file, rounds, tmp_path):
    log = tmp_path / "faults.jsonl"
    env = dict(os.environ, ROS_HOME=str(tmp_path), ROS_LOG_DIR=str(tmp_path / "log"), RBD_FAULT_LOG=str(log))
    proc = subprocess.run(["rostest", "--text", "rbd_bringup", test_file, "repeat:=%d" % rounds], env=env,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=1400)
    out = proc.stdout
    assert proc.returncode == 0 and "RESULT: SUCCESS" in out, out[-8000:]
    # every fault of every round measured: one FAULT_RESULT per injection at least
    runs = collections.Counter(json.loads(line)["fault"] for line in log.read_text().splitlines() if line.strip())
    short = {name: runs[name] for name in every_round_faults(test_file) if runs[name] < rounds}
    assert not short, "faults measured fewer than %d times: %r (all: %r)" % (rounds, short, dict(runs))
