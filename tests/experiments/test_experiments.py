"""The thesis experiments in their short form (make test) plus the ROS-free maths behind them.

One `run_all --short --parallel` run (two simulator stacks at once; conftest.py) feeds every system
test below; the bounds come from the thesis / DESIGN (tests/experiments/thesis.py), never from a
previous result. RBD_EXPERIMENTS_OUT keeps the output directory.
"""

import json
import math
import os
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import analysis  # noqa: E402
import thesis  # noqa: E402
from short_run import result  # noqa: E402

# ---------------------------------------------------------------------------------------------
# ROS-free: the measurement maths
# ---------------------------------------------------------------------------------------------


def first_order(t_step, t_end, amp, delay, tau, overshoot=0.0):
    out = []
    for i in range(400):
        t = i * 0.01
        v = 0.0
        if t_step + delay <= t <= t_end:
            x = (t - t_step - delay) / tau
            v = amp * (1 - math.exp(-x)) * (1 + overshoot * math.exp(-x) * math.sin(x))
        out.append((t, v))
    return out


def test_step_metrics_of_a_delayed_first_order_response():
    m = analysis.step_metrics(first_order(1.0, 3.0, 0.3, 0.08, 0.05), 1.0, 3.0, 0.3)
    assert m["dead_time_s"] == pytest.approx(0.09, abs=0.011)  # first 10 % sample after the delay
    assert m["rise_time_s"] == pytest.approx(0.05 * math.log(9), abs=0.02)
    assert m["overshoot_pct"] == pytest.approx(0.0, abs=1e-9)
    assert m["steady_state_error_pct"] < 0.1


def test_step_metrics_see_overshoot_and_a_wrong_plateau():
    m = analysis.step_metrics(first_order(0.0, 3.0, -0.5, 0.0, 0.1, overshoot=2.0), 0.0, 3.0, -0.5)
    assert m["overshoot_pct"] > 10.0
    low = [(t, 0.8 * v) for t, v in first_order(0.0, 3.0, 0.5, 0.0, 0.1)]
    assert analysis.step_metrics(low, 0.0, 3.0, 0.5)["steady_state_error_pct"] == pytest.approx(20.0, abs=0.5)
    none = analysis.step_metrics([(t, 0.0) for t, _ in low], 0.0, 3.0, 0.5)
    assert none["dead_time_s"] is None and none["rise_time_s"] is None


def test_step_metrics_reject_bad_input():
    with pytest.raises(ValueError):
        analysis.step_metrics([(0.5, 1.0)], 0.0, 1.0, 0.0)
    with pytest.raises(ValueError):
        analysis.step_metrics([(0.5, 1.0)], 1.0, 1.0, 1.0)
    with pytest.raises(ValueError):
        analysis.step_metrics([(5.0, 1.0)], 0.0, 1.0, 1.0)


def test_ramp_slope():
    assert analysis.ramp_slope([(t * 0.1, 0.3 * t * 0.1 + 2) for t in range(20)]) == pytest.approx(0.3)
    with pytest.raises(ValueError):
        analysis.ramp_slope([(1.0, 2.0)])


def test_expected_trigger_distance_on_the_axes_and_the_corner():
    zone = (0.70, 0.55, 0.35, 0.35)
    assert analysis.expected_trigger_distance(0.0, 0.2, zone) == pytest.approx(0.90, abs=1e-6)
    assert analysis.expected_trigger_distance(math.pi, 0.2, zone) == pytest.approx(0.75, abs=1e-6)
    assert analysis.expected_trigger_distance(math.pi / 2, 0.2, zone) == pytest.approx(0.55, abs=1e-6)
    # Towards the front-left corner the cylinder touches the corner: |centre - corner| = r.
    a = math.atan2(0.35, 0.70)
    d = analysis.expected_trigger_distance(a, 0.2, zone)
    assert math.hypot(d * math.cos(a) - 0.70, d * math.sin(a) - 0.35) == pytest.approx(0.2, abs=1e-6)


def test_find_flip_bisects_and_refuses_a_bad_bracket():
    calls = []

    def probe(d):
        calls.append(d)
        return d <= 0.7234

    assert analysis.find_flip(probe, 0.4, 1.0, 0.005) == pytest.approx(0.7234, abs=0.005)
    assert len(calls) < 12
    assert analysis.find_flip(lambda d: True, 0.4, 1.0, 0.01) is None  # trips even far away
    assert analysis.find_flip(lambda d: False, 0.4, 1.0, 0.01) is None  # never trips


def test_lowest_true_bisects_up_and_refuses_a_bad_bracket():
    calls = []

    def taller_than(h):
        calls.append(h)
        return h >= 0.137

    h = analysis.lowest_true(taller_than, 0.0, 0.6, 0.01)
    assert 0.137 <= h < 0.147 and taller_than(h)
    assert len(calls) <= 2 + 7 + 1
    assert analysis.lowest_true(lambda h: False, 0.0, 0.6, 0.01) is None  # never seen
    assert analysis.lowest_true(lambda h: True, 0.0, 0.6, 0.01) is None  # seen even at 0: bad bracket


def test_rows_pass_and_fail_on_the_thesis_bounds():
    good = {"path": {"max_deviation_m": 0.05, "total_time_s": 25.0, "final_position_error_m": 0.01, "full": True},
            "boundary": {"sides": [{"side": "front", "target_m": 0.7, "measured_m": 0.75}]},
            "rotation": {"with_correction": {"drift_from_start_m": 0.1, "peak_wz_deg_s": 36.0},
                         "without_correction": {"drift_from_start_m": 0.4, "peak_wz_deg_s": 36.0}}}
    assert all(r["ok"] is not False for r in thesis.rows(good))
    bad = json.loads(json.dumps(good))
    bad["path"]["max_deviation_m"] = 0.25
    bad["boundary"]["sides"][0]["measured_m"] = 0.79
    bad["rotation"]["with_correction"]["drift_from_start_m"] = 0.25
    failed = [r["figure"] for r in thesis.rows(bad) if r["ok"] is False]
    assert any(f.startswith("21") for f in failed)
    assert any(f.startswith("23") for f in failed)
    assert any(f.startswith("20") for f in failed)


def test_rows_of_an_experiment_that_raised_are_one_failed_row():
    # A CI run lost every result when `reaction` raised: rows() read its missing keys and crashed,
    # so run_all wrote no results.json and the experiment's own error was never shown.
    names = ("step", "rotation", "path", "zone", "boundary", "reaction", "detect", "stopping", "box", "wall",
             "visitor")
    table = thesis.rows({name: {"error": "%s broke" % name} for name in names})
    assert [r["figure"] for r in table] == sorted(names)
    assert all(r["ok"] is False and r["ours"] == "%s broke" % r["figure"] for r in table)


def test_readme_markers_are_replaced_not_duplicated():
    text = "intro\n%s\nold table\n%s\nrest\n" % (thesis.MARK_BEGIN, thesis.MARK_END)
    once = thesis.update_readme(text, "| new |\n")
    twice = thesis.update_readme(once, "| newer |\n")
    assert "old table" not in once and "| new |" in once and once.endswith("rest\n")
    assert twice.count(thesis.MARK_BEGIN) == 1 and "| new |" not in twice and "| newer |" in twice
    with pytest.raises(ValueError):
        thesis.update_readme("no markers", "x")


def test_root_readme_table_is_the_generated_one():
    """The README section is run_all's output: the rendering of docs/experiments/results.json."""
    root = os.path.dirname(os.path.dirname(HERE))
    with open(os.path.join(root, "README.md")) as fh:
        text = fh.read()
    assert thesis.MARK_BEGIN in text and thesis.MARK_END in text
    section = text.split(thesis.MARK_BEGIN)[1].split(thesis.MARK_END)[0]
    with open(os.path.join(root, "docs", "experiments", "results.json")) as fh:
        committed = json.load(fh)
    assert thesis.render_table(committed["rows"]) in section
    assert not committed["results"].get("short"), "the README shows the full runs"
    for name in ("step", "rotation", "path", "zone", "boundary", "reaction", "box", "wall", "visitor"):
        assert "error" not in committed["results"][name], name
        assert not committed["results"][name]["short"], name
    for line in section.splitlines():
        if line.startswith("!["):
            png = os.path.join(root, line.split("(")[1].rstrip(")"))
            assert 5000 < os.path.getsize(png) < 150000, png


# ---------------------------------------------------------------------------------------------
# The short experiments on the simulator (both stacks in parallel, one run for all tests)
# ---------------------------------------------------------------------------------------------


# short_run: conftest.py's one `run_all --short --parallel --mount-check` (shared with test_mount_zone.py)


def test_fig18_steps_integrate_with_small_latency(short_run):
    step = result(short_run, "step")
    for axis in ("x", "y", "yaw"):
        m = step[axis]
        assert m["dead_time_s"] is not None, axis
        assert m["dead_time_s"] <= thesis.THESIS_LATENCY_S + thesis.LOAD_MARGIN_S, (axis, m)
        assert m["steady_state_error_pct"] <= thesis.STEP_SS_ERROR_PCT, (axis, m)
        # Integrating behaviour: the output position/angle grows at the commanded rate.
        assert m["ramp_slope_ratio"] == pytest.approx(1.0, abs=thesis.STEP_SS_ERROR_PCT / 100.0), (axis, m)
    assert os.path.getsize(step["png"]) > 10000


def test_fig19_20_rotation_drift_and_its_correction(short_run):
    rot = result(short_run, "rotation")
    without = rot["without_correction"]["drift_from_start_m"]
    with_pc = rot["with_correction"]["drift_from_start_m"]
    # The mock A1 reproduces the thesis' drift (0.4 m per 180 deg) ...
    assert without == pytest.approx(thesis.THESIS_DRIFT_180_M, rel=0.25)
    # ... and the position hold cuts it by more than the thesis' factor of two.
    assert without >= thesis.THESIS_DRIFT_RATIO * with_pc
    assert rot["with_correction"]["peak_wz_deg_s"] <= thesis.THESIS_MAX_WZ_DEG_S + 1.0
    assert rot["with_correction"]["final_yaw_error_deg"] < 3.0


def test_fig22_zone_shape_matches_the_configured_cuboid(short_run):
    zone = result(short_run, "zone")
    assert zone["zone_m"] == pytest.approx(list(thesis.THESIS_ZONE_M))
    assert len(zone["points"]) >= 4
    for p in zone["points"]:
        assert p["measured_centre_m"] is not None, p
        assert abs(p["error_m"]) <= thesis.THESIS_BOUNDARY_TOL_M, p
        # The published collision state (not only the per-scan count) goes true just inside.
        assert p["state_confirmed"], p


def test_fig23_boundary_within_80_mm(short_run):
    sides = result(short_run, "boundary")["sides"]
    assert [s["target_m"] for s in sides] == pytest.approx(list(thesis.THESIS_ZONE_M))  # front, back, left, right
    for s in sides:
        assert s["measured_m"] is not None, s
        assert abs(s["measured_m"] - s["target_m"]) <= thesis.THESIS_BOUNDARY_TOL_M, s


def test_reaction_time_every_intrusion_stops_within_a_scan(short_run):
    r = result(short_run, "reaction")
    assert r["stopped"] == r["trials"] >= 2
    assert len(r["times_s"]) >= r["trials"] - 1  # an onset may fall while already standing
    assert r["p99_s"] <= r["scan_period_s"] + thesis.REACTION_EXTRA_S + thesis.LOAD_MARGIN_S
    # Measured on ground truth: the body stands still within the thesis' maximum allowed reaction.
    assert r["truth_stop_s"], "no ground-truth stop measured"
    assert r["truth_stop_max_s"] <= thesis.THESIS_REACTION_MAX_S + thesis.LOAD_MARGIN_S


# ---------------------------------------------------------------------------------------------
# Issue 17: active collision avoidance, on ground truth
# ---------------------------------------------------------------------------------------------
def test_visitor_is_dodged_within_dodge_max_and_the_robot_returns_home(short_run):
    runs = result(short_run, "visitor")["runs"]
    assert runs
    for r in runs:
        assert r["dodged"] and r["contacts"] == 0, r["states"]
        assert r["max_offset_m"] <= r["dodge_max_m"] + thesis.DODGE_SLACK_M
        assert r["returned"] and r["final_offset_m"] <= thesis.HOME_TOL_M
        assert r["arena_exit_samples"] == 0


def test_table_written_and_every_bounded_row_passes(short_run):
    with open(os.path.join(short_run["out"], "table.md")) as fh:
        table = fh.read()
    assert table.startswith("| Fig. |")
    failed = [r for r in short_run["rows"] if r["ok"] is False]
    assert not failed, failed


def test_table_cells_with_pipes_do_not_break_the_markdown():
    table = thesis.render_table([{"figure": "a|b", "quantity": "q", "thesis": "t", "ours": "o", "bound": "",
                                  "ok": True}])
    assert table.splitlines()[2] == "| a\\|b | q | t | o |  | yes |"
