"""The robot's status light mirrors the operator GUI's state colours (rbd_local.gui.app.STATUS_COLOURS)."""

import pytest

from rbd_a1_driver.led import STATUS_RGB, UNKNOWN_RGB, led_bytes, led_colour

app = pytest.importorskip("rbd_local.gui.app")  # the laptop app (venv): the GUI is the truth


def rgb(hex_colour):
    return tuple(int(hex_colour[i:i + 2], 16) for i in (1, 3, 5))


def test_colours_are_the_guis():
    assert {status: rgb(c) for status, c in app.STATUS_COLOURS.items()} == STATUS_RGB
    assert rgb(app.UNKNOWN_COLOUR) == UNKNOWN_RGB


@pytest.mark.parametrize("status", ["emergency", "collision", "idle", "running", "", "whatever"])
def test_led_follows_status_and_estop_is_red(status):
    assert led_colour(status, False) == (rgb(app.STATUS_COLOURS[status]) if status in app.STATUS_COLOURS
                                         else rgb(app.UNKNOWN_COLOUR))
    assert led_colour(status, True) == rgb(app.STATUS_COLOURS["emergency"])


def test_four_leds_same_colour():
    assert led_bytes((1, 2, 3)) == bytes([1, 2, 3] * 4)
