"""Crowd soak (issue 10): the report's bookkeeping, and a short soak of the whole simulated stack.

The long soak is `make soak` (tests/soak/run, 1 hour by default); here the same driver runs for
40 s (RBD_SOAK_SECONDS overrides) and its ground-truth report is asserted.
"""

import json
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "soak"))

import soak_report  # noqa: E402


def test_linear_slope():
    assert soak_report.linear_slope([(0, 1.0), (1, 3.0), (2, 5.0)]) == pytest.approx(2.0)
    assert soak_report.linear_slope([(0, 1.0)]) == 0.0
    assert soak_report.linear_slope([(1, 1.0), (1, 2.0)]) == 0.0


def test_memory_trend_flags_a_steady_leak_only():
    flat = [(t, 50.0 + (0.3 if t % 10 else 0.0)) for t in range(0, 3600, 5)]
    assert soak_report.memory_trend(flat, 300)["flat"]
    # 30 MB/h for an hour: slope and growth both beyond the bounds.
    leak = [(t, 50.0 + 30.0 * t / 3600.0) for t in range(0, 3600, 5)]
    m = soak_report.memory_trend(leak, 300)
    assert not m["flat"]
    assert m["slope_mb_per_h"] == pytest.approx(30.0, rel=0.01)
    assert m["start_mb"] == 50.0 and m["end_mb"] == pytest.approx(80.0, abs=0.1)
    # A start-up allocation inside the warm-up does not count.
    startup = [(t, 40.0 if t < 60 else 90.0) for t in range(0, 600, 5)]
    assert soak_report.memory_trend(startup, 120)["flat"]
    # A short run cannot fail on a noisy slope alone (growth below the absolute bound).
    short = [(0, 50.0), (5, 50.0), (10, 50.0), (15, 51.0)]
    assert soak_report.memory_trend(short, 0)["flat"]


def test_launch_events_parse_roslaunch_output():
    lines = [
        "[rbd_lidar-12] process has died [pid 123, exit code -9, cmd ...].\n",
        "[rbd_lidar-12] restarting process\n",
        "[rbd_controller-3] process has finished cleanly\n",
    ]
    assert soak_report.launch_events(lines) == (["rbd_lidar-12"], ["rbd_lidar-12"])


def test_state_counter_tricks_and_collision_stops():
    c = soak_report.StateCounter()
    seq = ["EMERGENCY_STOP", "WAITING_FOR_GESTURE", "GENERATING_PATH", "EXECUTING", "COLLISION_DETECTED",
           "EXECUTING", "WAITING_FOR_GESTURE", "GENERATING_PATH", "EXECUTING", "WAITING_FOR_GESTURE",
           "EMERGENCY_STOP", "WAITING_FOR_GESTURE"]
    for t, s in enumerate(seq):
        c.update(float(t), s)
    assert c.tricks_completed == 2
    assert (c.collision_stops, c.collision_resumes) == (1, 1)
    assert c.emergency_stops == 1
    assert c.longest_gap_s == 3.0


def _report(**kw):
    r = {"contacts": [], "node_deaths": [], "respawns": [], "vanished_nodes": [], "memory": {"a": {"flat": True}},
         "tricks_completed": 3, "error": ""}
    r.update(kw)
    return r


@pytest.mark.parametrize(
    "change, match",
    [
        ({"contacts": [[1.0, "crowd3"]]}, "contact"),
        ({"node_deaths": ["rbd_lidar-5"]}, "node crash"),
        ({"respawns": ["rbd_controller"]}, "node crash"),
        ({"vanished_nodes": ["os1_sim"]}, "node crash"),
        ({"memory": {"os1_sim": {"flat": False}}}, "memory growth.*os1_sim"),
        ({"tricks_completed": 0}, "no trick"),
        ({"error": "RuntimeError: x"}, "driver error"),
    ],
)
def test_verdict_fails_on_each_condition(change, match):
    assert soak_report.verdict(_report()) == []
    reasons = soak_report.verdict(_report(**change))
    assert len(reasons) == 1 and __import__("re").search(match, reasons[0]), reasons


def test_box_watch_explains_a_contact():
    w = soak_report.BoxWatch(keep_s=5.0)
    w.on_state(0.0, "EXECUTING")
    for i in range(11):  # walking at 0.3 m/s along x
        w.on_truth(i * 0.1, (0.03 * i, 0.0, 0.0), (0.3, 0.0, 0.0))
    drop = w.on_drop(1.0, "box0", (0.8, 0.0, 0.0, 0.4, 0.4), gap=0.15, zone_gap=0.0)
    assert drop["gap_m"] == 0.15 and drop["speed_mps"] == 0.3 and drop["state"] == "EXECUTING"
    w.on_zone(1.05, False, True)  # a stale report before the box was seen
    w.on_zone(1.2, True, False)  # first collision after the drop
    for i in range(11, 16):
        w.on_truth(i * 0.1, (0.03 * i, 0.0, 0.0), (0.3, 0.0, 0.0))
    w.on_state(1.3, "COLLISION_DETECTED")
    w.on_clearance(1.5, "box0", 0.0)
    w.on_clearance(1.4, "box0", 0.02)  # not smaller: the minimum stays
    info = w.on_contact(1.5, "box0")
    assert info["state"] == "COLLISION_DETECTED" and info["since_drop_s"] == 0.5
    assert info["first_zone_collision_after_drop_s"] == 0.2
    assert info["moved_since_first_zone_collision_m"] == pytest.approx(0.09, abs=1e-6)  # 1.2 s -> 1.5 s at 0.3 m/s
    assert info["stale_zone_reports_last_3s"] == 1 and info["zone_collision_now"] is True
    assert [s for _, s in info["states_since_drop"]] == ["EXECUTING", "COLLISION_DETECTED"]
    assert drop["min_clearance_m"] == 0.0 and drop["min_clearance_state"] == "COLLISION_DETECTED"
    assert drop["clearance_3s_m"] == 0.0  # within 3 s of the drop: the stop for it
    w.on_clearance(5.0, "box0", -1.0)  # 4 s later (an overlap later on): not part of the stop any more
    assert drop["clearance_3s_m"] == 0.0 and drop["min_clearance_m"] == -1.0
    assert w.contacts == [info]


def test_short_crowd_soak(tmp_path):
    seconds = float(os.environ.get("RBD_SOAK_SECONDS", "40"))
    out = tmp_path / "soak"
    proc = subprocess.run(
        [sys.executable, os.path.join(ROOT, "tests", "soak", "run"), "--duration", str(seconds), "--out", str(out),
         "--memory-period", "2", "--seed", "3"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=seconds + 240,
    )
    assert (out / "report.json").exists(), proc.stdout[-5000:]
    report = json.loads((out / "report.json").read_text())
    assert report["error"] == "", report["error"]
    assert report["duration_s"] >= seconds
    assert report["people"] == 12 and 0.5 <= report["max_person_speed"] <= 1.5
    # Ground truth was really watched: ~100 Hz samples, people model == the world's markers.
    assert report["truth_samples"] > 20 * seconds
    assert report["marker_messages"] > 2 * seconds
    assert report["marker_model_max_deviation_m"] < 0.01
    assert report["contacts"] == [], report["contacts"]
    assert report["min_clearance_m"] is not None and report["min_clearance_m"] > 0.0
    # The robot worked: gestures over the bridge, tricks done, the robot moved.
    assert report["gestures_sent"] >= seconds / 2
    assert report["tricks_completed"] >= 1, proc.stdout[-3000:]
    assert report["robot_path_m"] > 0.5
    assert report["node_deaths"] == [] and report["respawns"] == [] and report["vanished_nodes"] == []
    for node in ("rbd_controller", "rbd_pos_controller", "rbd_lidar", "rbd_bridge", "os1_sim", "mock_a1", "world"):
        assert report["memory"][node]["samples"] >= 5, (node, report["memory"].get(node))
    assert all(m["flat"] for m in report["memory"].values())
    assert report["passed"] and proc.returncode == 0, proc.stdout[-3000:]
    assert "RoboDog crowd soak: PASS" in (out / "report.txt").read_text()
