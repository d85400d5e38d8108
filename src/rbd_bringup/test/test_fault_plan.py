"""fault_plan: which faults the faults rostests run in which round (``faults:="a b:1"``, ``repeat:=N``)."""

import importlib.util
import os

import pytest

_HERE = os.path.dirname(os.path.abspath(__file__))


@pytest.fixture(scope="module")
def fault_plan():
    path = os.path.join(_HERE, "rostest", "test_faults.py")
    spec = importlib.util.spec_from_file_location("rbd_bringup_faults_rostest", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.fault_plan


def test_a_plain_name_runs_in_every_round_in_the_order_given(fault_plan):
    assert fault_plan("estop zed2_stale", 3) == [["estop", "zed2_stale"]] * 3


def test_name_n_runs_in_the_last_n_rounds_only(fault_plan):
    assert fault_plan("estop remote_estop:2 estop_states:1", 3) == [
        ["estop"],
        ["estop", "remote_estop"],
        ["estop", "remote_estop", "estop_states"],
    ]
    assert fault_plan("remote_estop:3", 3) == [["remote_estop"]] * 3


@pytest.mark.parametrize("spec", ["estop:0", "estop:4", "estop:-1"])
def test_rounds_outside_1_to_repeat_are_refused(fault_plan, spec):
    with pytest.raises(ValueError, match="rounds must be 1..3"):
        fault_plan(spec, 3)


def test_a_count_that_is_not_a_number_is_refused(fault_plan):
    with pytest.raises(ValueError):
        fault_plan("estop:two", 3)
