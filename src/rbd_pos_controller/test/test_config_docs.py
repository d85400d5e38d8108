"""config/default.yaml + each profile, the parameter classes and the README table name the same keys."""

import math
import os

import pytest
import yaml

from rbd_pos_controller.control_law import Gains
from rbd_pos_controller.params import Params

PKG = os.path.join(os.path.dirname(__file__), "..")
PROFILES = ("thesis_table2", "sim_tuned")
PROFILE_KEYS = {"k_x", "k_y", "k_alpha", "max_vx", "max_vy", "max_wz", "k_hold", "max_v_hold"}


def load(*parts):
    with open(os.path.join(PKG, "config", *parts)) as fh:
        return yaml.safe_load(fh)


def test_default_yaml_and_profiles_keys_match_params_and_readme():
    base = set(load("default.yaml"))
    assert not base & PROFILE_KEYS, "profile keys belong in config/profiles/"
    node_only = {"rate", "body_pose_timeout"}
    expected = set(Gains.__slots__) | (set(Params.__slots__) - {"gains"}) | node_only
    for name in PROFILES:
        profile = set(load("profiles", name + ".yaml"))
        assert profile == PROFILE_KEYS, name
        assert base | profile == expected, name
    with open(os.path.join(PKG, "README.md")) as fh:
        readme = fh.read()
    for key in expected:
        assert "`~%s`" % key in readme, key
    for name in PROFILES:
        assert "`%s`" % name in readme, name


@pytest.mark.parametrize("name", PROFILES)
def test_profiles_are_valid(name):
    data = dict(load("default.yaml"), **load("profiles", name + ".yaml"))
    gains = Gains(**{k: data[k] for k in Gains.__slots__})
    Params(gains=gains, **{k: data[k] for k in Params.__slots__ if k != "gains"})
    # Both keep Table 2's saturations.
    assert (gains.max_vx, gains.max_vy) == (0.3, 0.12)
    assert gains.max_wz == pytest.approx(math.radians(36.0), abs=1e-6)


def test_thesis_profile_is_table_2():
    """Thesis Table 2: k_x 2.5 /s (+-0.3 m/s), k_y 2.0 /s (+-0.12 m/s), k_alpha 1.0 /s (+-36 deg/s)."""
    p = load("profiles", "thesis_table2.yaml")
    assert (p["k_x"], p["k_y"], p["k_alpha"]) == (2.5, 2.0, 1.0)
    assert p["max_v_hold"] <= 0.12  # the sideways hold stays within Table 2's sideways saturation


def test_launch_file_default_profile_is_the_thesis_one():
    with open(os.path.join(PKG, "launch", "rbd_pos_controller.launch")) as fh:
        text = fh.read()
    assert 'name="profile" default="thesis_table2"' in text
