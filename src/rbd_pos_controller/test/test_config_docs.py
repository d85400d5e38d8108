"""config/default.yaml, the parameter classes and the README table name the same keys."""

import os

import yaml

from rbd_pos_controller.control_law import Gains
from rbd_pos_controller.controller import Params

PKG = os.path.join(os.path.dirname(__file__), "..")


def test_default_yaml_keys_match_params_and_readme():
    with open(os.path.join(PKG, "config", "default.yaml")) as fh:
        keys = set(yaml.safe_load(fh))
    node_only = {"rate", "body_pose_timeout"}
    assert keys == set(Gains.__slots__) | (set(Params.__slots__) - {"gains"}) | node_only
    with open(os.path.join(PKG, "README.md")) as fh:
        readme = fh.read()
    for key in keys:
        assert "`~%s`" % key in readme, key


def test_default_yaml_values_are_valid():
    with open(os.path.join(PKG, "config", "default.yaml")) as fh:
        data = yaml.safe_load(fh)
    gains = Gains(**{k: data[k] for k in Gains.__slots__})
    Params(gains=gains, **{k: data[k] for k in Params.__slots__ if k != "gains"})
    assert (gains.max_vx, gains.max_vy) == (0.3, 0.12)
