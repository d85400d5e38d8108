import math
import os

import pytest

from rbd_pos_controller.runlog import RunLog, metrics, plot, segment_distance


def example():
    log = RunLog((0.0, 0.0, 0.0))
    log.goals = [(0.0, 1.0, 0.0, 0.0), (5.0, -1.0, 0.0, math.pi)]
    log.poses = [
        (0.0, 0.0, 0.0, 0.0),
        (2.0, 0.5, 0.1, 0.0),
        (4.0, 1.0, 0.0, 0.0),
        (6.0, 0.0, -0.2, math.pi),
        (9.0, -1.01, 0.0, 3.1),
    ]
    log.cmds = [(0.0, 0.3, 0.0, 0.0), (4.0, 0.0, 0.0, 0.6), (9.0, 0.0, 0.0, 0.0)]
    log.done = 9.5
    return log


def test_metrics():
    m = metrics(example())
    assert m["max_deviation_m"] == pytest.approx(0.2)
    assert m["total_time_s"] == pytest.approx(9.5)
    assert m["final_position_error_m"] == pytest.approx(0.01)
    assert m["final_yaw_error_deg"] == pytest.approx(math.degrees(math.pi - 3.1))
    assert m["drift_from_start_m"] == pytest.approx(1.01)


def test_segment_distance():
    assert segment_distance((0.5, 1.0), (0.0, 0.0), (1.0, 0.0)) == pytest.approx(1.0)
    assert segment_distance((2.0, 0.0), (0.0, 0.0), (1.0, 0.0)) == pytest.approx(1.0)
    assert segment_distance((3.0, 4.0), (0.0, 0.0), (0.0, 0.0)) == pytest.approx(5.0)


def test_roundtrip_and_plot(tmp_path):
    path = str(tmp_path / "run.json")
    example().save(path)
    log = RunLog.load(path)
    assert metrics(log) == metrics(example())
    files = plot(log, str(tmp_path / "run"))
    assert len(files) == 2
    for f in files:
        with open(f, "rb") as fh:
            assert fh.read(8) == b"\x89PNG\r\n\x1a\n"
        assert os.path.getsize(f) > 5000


@pytest.mark.parametrize(
    "data", [{}, {"start": [0, 0, 0], "poses": [], "goals": []}, {"start": "x", "poses": [], "goals": []}]
)
def test_malformed_log_rejected(data):
    with pytest.raises(ValueError):
        RunLog.from_dict(data)


def test_unwrap():
    from rbd_pos_controller.runlog import unwrap

    assert unwrap([3.0, -3.0, -2.0]) == pytest.approx([3.0, 2 * math.pi - 3.0, 2 * math.pi - 2.0])
