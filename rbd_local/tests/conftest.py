"""Test setup: import this checkout's rbd_local (not an installed copy) and share fixtures.

The repository's test kit (``src/rbd_testkit``: SIGINT guard, ``ros_env``, ``wait_for``...) comes in
as a pytest plugin; it is on the path after ``source ./env.sh`` and added from the source tree otherwise.
"""

import atexit
import os
import shutil
import sys
import tempfile

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

# Teach mode keeps taught gestures in $XDG_DATA_HOME/rbd_local; the tests must neither read
# nor write the user's own file.
_DATA_HOME = tempfile.mkdtemp(prefix="rbd-local-test-data.")
os.environ["XDG_DATA_HOME"] = _DATA_HOME
atexit.register(shutil.rmtree, _DATA_HOME, True)


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


@pytest.fixture(scope="session")
def hand_sprites(hand_photos):
    """Hand sprites of both real photos (for real-photo clips)."""
    from rbd_local.evaluation import load_sprites

    return load_sprites([hand_photos["handSrc.jpg"], hand_photos["handDst.jpg"]])


@pytest.fixture(scope="session")
def display():
    """A private Xvfb for the session's windows; DISPLAY points at it meanwhile.

    One for the whole session: Tk ends the process when the X server of a window it still
    knows goes away, so a display must outlive every Tk interpreter of the session.
    """
    if shutil.which("Xvfb") is None:
        pytest.skip("Xvfb not installed")
    from xvfb import Xvfb

    x = Xvfb("1280x800x24").start()
    old = os.environ.get("DISPLAY")
    os.environ["DISPLAY"] = x.display
    yield x.display
    if old is None:
        os.environ.pop("DISPLAY", None)
    else:
        os.environ["DISPLAY"] = old
    x.stop()
