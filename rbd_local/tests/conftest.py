"""Test setup: import this checkout's rbd_local (not an installed copy) and share fixtures.

The repository's test kit (``src/rbd_testkit``: SIGINT guard, ``ros_env``, ``wait_for``...) comes in
as a pytest plugin; it is on the path after ``source ./env.sh`` and added from the source tree otherwise.
"""

import os
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
PKG_ROOT = os.path.dirname(HERE)
try:
    import rbd_testkit  # noqa: F401
except ImportError:
    sys.path.insert(0, os.path.join(os.path.dirname(PKG_ROOT), "src", "rbd_testkit", "src"))

pytest_plugins = ["rbd_testkit.pytest_plugin"]
sys.path.insert(0, os.path.join(PKG_ROOT, "src"))
sys.path.insert(0, HERE)
for _name in [m for m in sys.modules if m == "rbd_local" or m.startswith("rbd_local.")]:
    del sys.modules[_name]

CACHE = os.path.join(PKG_ROOT, ".cache")


@pytest.fixture(scope="session")
def hand_photos():
    """Paths of the two real hand photos from Debian's opencv-doc (fetched once, cached)."""
    from rbd_local.testdata import fetch_hand_photos

    return fetch_hand_photos(os.path.join(CACHE, "hand_photos"))


@pytest.fixture(scope="session")
def shipped_model():
    from rbd_local.gestures.config import DEFAULT_MODEL
    from rbd_local.gestures.model import GestureModel

    return GestureModel.load(DEFAULT_MODEL)


@pytest.fixture
def fake_bridge():
    from fake_bridge import FakeBridge

    bridge = FakeBridge().start()
    yield bridge
    bridge.stop()
