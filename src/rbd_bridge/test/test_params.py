"""Numeric node parameters in the forms roslaunch and rosbridge's launch files pass them."""

import pytest

from rbd_bridge.core.params import ParamError, number


@pytest.mark.parametrize("unset", [None, "None", "none", "", "  ", "null", "default"])
def test_unset_forms_give_the_default(unset):
    # rosbridge_websocket.launch passes max_message_size as the text "None" when unset
    assert number("max_message_size", unset, 10000000) == 10000000


@pytest.mark.parametrize(
    "value, kind, expected",
    [
        (4096, int, 4096),
        ("4096", int, 4096),
        (4096.0, int, 4096),
        ("1e6", int, 1000000),
        ("2.5", float, 2.5),
        (3, float, 3.0),
    ],
)
def test_numbers_in_every_form(value, kind, expected):
    got = number("x", value, 0, kind)
    assert got == expected and type(got) is kind


@pytest.mark.parametrize("bad", ["abc", "12abc", True, False, [1], {"a": 1}, "nan", 1.5, "1.5"])
def test_bad_values_raise_a_clear_error(bad):
    with pytest.raises(ParamError) as err:
        number("max_message_size", bad, 10, int)
    assert "~max_message_size" in str(err.value)


def test_minimum_is_enforced():
    assert number("port", "0", 9090, int, minimum=0) == 0
    with pytest.raises(ParamError, match=">= 0"):
        number("port", -1, 9090, int, minimum=0)
    with pytest.raises(ParamError):
        number("ping", "nan", 20.0, float)
