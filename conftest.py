"""Shared pytest setup of the repository: the test kit's plugin (SIGINT guard, ``ros_env`` fixture).

The helpers themselves live in one place, ``src/rbd_testkit`` (``from rbd_testkit import ...``):
on the path after ``source ./env.sh``, and added here from the source tree otherwise.
"""

import os
import sys

try:
    import rbd_testkit  # noqa: F401
except ImportError:
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "src", "rbd_testkit", "src"))

pytest_plugins = ["rbd_testkit.pytest_plugin"]

LONG = "RBD_TEST_LONG"  # 1: also the tests marked `long` (make test-long); see README "Tests"


def pytest_collection_modifyitems(config, items):
    """Deselect the tests marked ``long`` unless RBD_TEST_LONG=1 (``make test-long`` sets it)."""
    if os.environ.get(LONG) == "1":
        return
    long_items = [item for item in items if item.get_closest_marker("long")]
    if long_items:
        config.hook.pytest_deselected(items=long_items)
        items[:] = [item for item in items if not item.get_closest_marker("long")]
