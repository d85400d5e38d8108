import pytest

from rbd_controller.cli import parse_estop_args


@pytest.mark.parametrize(
    "argv, expected", [(["on"], True), (["OFF"], False), (["release"], False), (["on", "__name:=x"], True)]
)
def test_valid(argv, expected):
    assert parse_estop_args(argv) is expected


@pytest.mark.parametrize("argv", [[], ["maybe"], ["on", "off"]])
def test_invalid(argv):
    assert parse_estop_args(argv) is None
