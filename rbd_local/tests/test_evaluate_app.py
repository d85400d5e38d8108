"""rbd-evaluate's failure-mode table: per-row no-command counts, rates, totals (no MediaPipe)."""

import argparse

import pytest

from rbd_local import evaluate_app


def test_random_counts_one_for_every_row_or_one_per_row():
    assert evaluate_app.random_counts("3", 7) == [3] * 7
    assert evaluate_app.random_counts("4, 10,15,12,30,4,4", 7) == [4, 10, 15, 12, 30, 4, 4]
    for bad in ("", "3,4", "-1", "x", "1,2,3,4,5,6,7,8"):
        with pytest.raises(ValueError, match="--random-clips"):
            evaluate_app.random_counts(bad, 7)


def _row(name, correct, clips, false_commands, seconds, fired):
    return {"condition": name, "detected": 90, "frames": 100, "lost_0_2": 1, "gesture_clips": clips,
            "longest_loss": 0.27, "correct": correct, "false_commands": false_commands,
            "none_seconds": seconds, "none_kinds": ["drift", "close"], "fired": fired}


def test_failure_table_rates_misses_and_the_rows_of_the_bar():
    rows = [_row("1 blur", 14, 16, 3, 60.0, {"wave": ["wave", "none", "none"], "circle": ["swipe_right", "circle"],
                                             "drift": ["push_down"]}),
            _row("2 a second hand", 16, 16, 1, 150.0, {"wave": ["wave"]}),
            _row("4 near hands", 15, 16, 0, 150.0, {"push_down": ["push_down"]})]
    args = argparse.Namespace(per_gesture=4, random_clips="4,10,15,12,30,4,4", max_hands=2)
    text = evaluate_app.failure_table(rows, args)
    lines = text.splitlines()
    row1 = next(x for x in lines if x.startswith("| 1 blur"))
    cells = [c.strip() for c in row1.strip("|").split("|")]
    assert cells[3] == "14/16 (88 %)"
    assert cells[4] == "circle: swipe_right; wave: none x2"  # drift is no gesture: not a miss
    assert cells[5] == "drift, close: 60 s" and cells[6] == "3" and cells[7] == "3.00"
    bar = next(x for x in lines if "issue's bar" in x)
    cells = [c.strip() for c in bar.strip("|").split("|")]
    assert cells[3] == "31/32 (97 %)"  # rows 2 and 4 only
    assert cells[5] == "300 s" and cells[6] == "1" and cells[7] == "**0.20**"
    total = next(x for x in lines if "all rows" in x)
    assert "45/48" in total and "360 s" in total
    assert "--random-clips 4,10,15,12,30,4,4" in text and "generated" in text


def test_failure_table_without_no_command_motion_has_no_rate():
    rows = [_row("6 low resolution", 8, 16, 0, 0.0, {})]
    text = evaluate_app.failure_table(rows, argparse.Namespace(per_gesture=4, random_clips="0", max_hands=2))
    cells = [c.strip() for c in text.splitlines()[2].strip("|").split("|")]
    assert cells[7] == "–" and cells[4] == "–"
    assert "issue's bar" not in text
