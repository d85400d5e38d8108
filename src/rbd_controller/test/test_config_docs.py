"""config/default.yaml keys are documented in the README parameter table."""

import os

import yaml

PKG = os.path.join(os.path.dirname(__file__), "..")


def test_default_yaml_keys_in_readme():
    with open(os.path.join(PKG, "config", "default.yaml")) as fh:
        keys = set(yaml.safe_load(fh))
    with open(os.path.join(PKG, "README.md")) as fh:
        readme = fh.read()
    for key in keys:
        assert "`~%s`" % key in readme, key
    with open(os.path.join(PKG, "nodes", "rbd_controller")) as fh:
        node = fh.read()
    for key in keys:
        assert '"~%s"' % key in node, key
