import os

import pytest
import yaml

from rbd_gestrec.gestures import GestureBuffer, GestureConfigError, parse_mapping, trick_names, with_tricks

CONFIG = os.path.join(os.path.dirname(__file__), "..", "config", "gestures.yaml")


def default_buffer(max_age=0.0):
    with open(CONFIG) as fh:
        return GestureBuffer(parse_mapping(yaml.safe_load(fh)), max_age)


def test_default_mapping_covers_the_four_tricks():
    with open(CONFIG) as fh:
        mapping = parse_mapping(yaml.safe_load(fh))
    assert set(mapping.values()) == {"walk", "spin", "wiggle", "lie_down"}


def test_each_gesture_returned_once_then_empty():
    buf = default_buffer()
    assert buf.take(0.0) == ""
    assert buf.push("spin", 1.0) == "spin"
    assert buf.take(1.1) == "spin"
    assert buf.take(1.2) == ""


def test_newest_gesture_wins():
    buf = default_buffer()
    buf.push("spin", 1.0)
    buf.push("walk", 2.0)
    assert buf.take(2.1) == "walk"
    assert buf.take(2.2) == ""


@pytest.mark.parametrize("label", ["dance", "", "SPIN", "rm -rf /", None, 42])
def test_unknown_gestures_are_filtered_and_do_not_clear_pending(label):
    buf = default_buffer()
    buf.push("wiggle", 1.0)
    assert buf.push(label, 1.5) is None
    assert buf.take(2.0) == "wiggle"


def test_mapping_translates_labels():
    buf = GestureBuffer(parse_mapping({"gestures": {"thumbs_up": "spin"}}))
    assert buf.push("spin", 0.0) is None
    assert buf.push(" thumbs_up ", 0.0) == "spin"
    assert buf.take(0.0) == "spin"


def test_old_gesture_dropped_when_max_age_set():
    buf = default_buffer(max_age=5.0)
    buf.push("spin", 0.0)
    assert buf.take(6.0) == ""
    buf.push("spin", 10.0)
    assert buf.take(14.0) == "spin"


@pytest.mark.parametrize(
    "data",
    [None, {}, {"gestures": {}}, {"gestures": {"a": ""}}, {"gestures": {"a": 3}}, {"gestures": {"": "spin"}}, []],
)
def test_invalid_mapping_rejected(data):
    with pytest.raises(GestureConfigError):
        parse_mapping(data)


TRICKS = os.path.join(os.path.dirname(__file__), "..", "..", "rbd_navigation", "config", "tricks.yaml")


def test_trick_names_are_accepted_as_labels_for_themselves():
    # the laptop publishes a taught gesture's trick name; rbd_navigation's YAML is the allow-list
    with open(TRICKS) as fh:
        names = trick_names(yaml.safe_load(fh))
    assert {"walk", "spin", "wiggle", "lie_down", "bow", "look_around", "sit", "shake"} <= set(names)
    with open(CONFIG) as fh:
        buf = GestureBuffer(with_tricks(parse_mapping(yaml.safe_load(fh)), names))
    assert buf.push("bow", 1.0) == "bow"
    assert buf.take(1.1) == "bow"
    assert buf.push("dance", 2.0) is None  # not a trick: still ignored
    # a mapping entry keeps its own command even when its label is also a trick's name
    mapped = GestureBuffer(with_tricks({"bow": "sit"}, ["bow", "walk"]))
    assert mapped.push("bow", 0.0) == "sit" and mapped.push("walk", 0.0) == "walk"


@pytest.mark.parametrize("bad", [{"tricks": "walk"}, [""], [3], {"tricks": {"": []}}])
def test_bad_trick_names_are_a_clear_error(bad):
    with pytest.raises(GestureConfigError):
        trick_names(bad)
    assert trick_names(None) == []
