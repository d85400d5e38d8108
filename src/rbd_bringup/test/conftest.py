"""Fixtures of rbd_bringup's launch tests (helpers in bringup_testing.py)."""

import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from bringup_testing import make_standins  # noqa: E402


@pytest.fixture(scope="session")
def standin_path(tmp_path_factory):
    """ROS_PACKAGE_PATH with the stand-in driver packages first."""
    root = make_standins(str(tmp_path_factory.mktemp("standin_drivers")))
    return root + os.pathsep + os.environ.get("ROS_PACKAGE_PATH", "")
