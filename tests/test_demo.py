"""System test: `make demo`'s scenario (tools/demo_scenario.py) on the whole simulated stack.

Asserts the report measured on ground truth: every trick completed, no contact with people or
the bag, the robot stopped for the visitor and resumed after the visitor left, and (with
RBD_AVOIDANCE_EXPERIMENTS=1, over make test's budget) it got around the bag put down on its
stroll (issue 17: obstacles avoided, time blocked).

Without the demo's OUT/recording (``--record-seconds 0``: ~10 s of recording nothing here asserts):
test_replay.py records with the same ``rosrun rbd_bringup record`` and replays it.
"""

import json
import os
import signal
import subprocess
import sys
import uuid

from rbd_testkit.process import kill_pids, pids_with_env

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TRICKS = ["walk", "spin", "wiggle", "lie_down", "bow"]
#: The stroll with the bag (issue 17) adds 100-130 s at load 2-5, over make test's serial-lane
#: budget: it runs with RBD_AVOIDANCE_EXPERIMENTS=1 (as tests/experiments/test_avoidance_experiments.py).
WITH_BAG = bool(os.environ.get("RBD_AVOIDANCE_EXPERIMENTS"))


def run_demo(args, timeout):
    """Run tools/demo_scenario.py ARGS; on a timeout stop it and every process of its stack.

    The scenario starts its master and roslaunch in sessions of their own, so killing the script
    alone would leave the simulated stack running: it gets SIGINT first (its own clean-up stops
    the stack), and whatever still carries this run's environment mark is killed after that.

    Returns:
        The CompletedProcess (stdout with stderr); the returncode is negative after a timeout.
    """
    mark = uuid.uuid4().hex
    env = dict(os.environ, RBD_TEST_DEMO_RUN=mark)
    proc = subprocess.Popen([sys.executable, os.path.join(ROOT, "tools", "demo_scenario.py")] + args, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True)
    try:
        stdout, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGINT)
        try:
            stdout, _ = proc.communicate(timeout=40.0)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            stdout, _ = proc.communicate()
        stdout += "\n[test_demo: timed out after %.0f s; stopped]" % timeout
    finally:
        kill_pids(pids_with_env("RBD_TEST_DEMO_RUN", mark))
    return subprocess.CompletedProcess(proc.args, proc.returncode, stdout)


def test_demo_scenario(tmp_path):
    out = tmp_path / "demo"
    tricks = TRICKS + (["stroll"] if WITH_BAG else [])
    proc = run_demo(["--out", str(out), "--columns", "512", "--tricks", ",".join(tricks), "--record-seconds", "0"]
                    + ([] if WITH_BAG else ["--bag", ""]), timeout=600)
    assert (out / "report.json").exists(), proc.stdout[-5000:]
    report = json.loads((out / "report.json").read_text())
    assert report["collisions_with_people"] == 0, report
    # "bow" is a gesture taught during the demo (teach mode) for a trick without a mapping entry;
    # "stroll" is sent by the operator and a bag is put down on its way (issue 17)
    assert report["tricks_completed"] == tricks, proc.stdout[-5000:]
    assert "real hand photos" in report["gesture_input"]
    if WITH_BAG:
        assert report["collisions_with_obstacles"] == 0, report
        assert report["min_distance_to_obstacle_m"] > 0.0, report
        assert report["obstacles_avoided"] >= 1, proc.stdout[-5000:]
        assert report["avoidance_gave_up"] == [], report
        # Stopped by the visitor and the bag, but not for ever: the bag costs the classification
        # (static after 5 s; the LiDAR map may know it sooner) per encounter, not the thesis' "forever".
        assert 1.0 < report["time_blocked_s"] < 60.0, report
        assert report["time_avoiding_s"] > 0.0, report
    assert report["collision_stops"] >= 1, "the robot never stopped for the visitor"
    assert report["resumes"] >= 1, ("the interrupted trick never resumed", [s["state"] for s in report["states"]])
    assert report["min_distance_to_person_m"] > 0.0
    assert report["final_position_error_m"] < 0.1
    assert (out / "run.png").stat().st_size > 10000
    assert (out / "demo.bag").exists()
    assert proc.returncode == 0, proc.stdout[-5000:]
