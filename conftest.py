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
