"""rbd_controller's tests import their shared scenes (fsm_scenes.py) from this directory."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
