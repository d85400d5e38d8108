"""The transition table's status words (the wire values of /rbd_pos_controller/status)."""

from rbd_pos_controller.fsm import MOTION_STATES, STATUS


def test_status_values():
    assert set(STATUS.values()) == {"idle", "running", "emergency", "collision"}
    assert all(STATUS[s] == "running" for s in MOTION_STATES)
