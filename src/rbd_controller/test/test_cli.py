import pytest

from rbd_controller.cli import parse_estop_args


@pytest.mark.parametrize(
    "argv, expected",
    [
        (["on"], True),
        (["OFF"], False),
        (["release"], False),
        (["on", "__name:=x"], True),
        (["estop:=/other/estop", "off"], False),  # a remap is not the word (startswith("__") missed it)
        (["_timeout:=2", "on", "__ns:=/robot"], True),
    ],
)
def test_valid(argv, expected):
    assert parse_estop_args(argv) is expected


@pytest.mark.parametrize("argv", [[], ["maybe"], ["on", "off"], ["a:=b"]])
def test_invalid(argv):
    assert parse_estop_args(argv) is None
