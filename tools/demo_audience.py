"""The demo's audience: the laptop app's gesture pipeline shown clips of a real hand (`make demo`).

Gestures go through the app's own recognition pipeline (MediaPipe on clips in which the real hand
of an opencv-doc photo is moved along a generated gesture path); a visitor teaches a new gesture
in teach mode. Used by tools/demo_scenario.py.
"""

import time

from demo_monitor import say

GESTURE_OF = {"walk": "swipe_right", "spin": "circle", "wiggle": "wave", "lie_down": "push_down"}
TAUGHT = ("checkmark", "bow")  # the gesture a visitor teaches, and its trick
GESTURE_INPUT = ("MediaPipe on clips of the real hand photos of opencv-doc moved along generated gesture "
                 "paths (real hand images, generated motion); 'bow' taught from 5 such clips in teach mode")


class Audience:
    """The laptop app's gesture pipeline feeding the robot link, shown real-photo clips."""

    def __init__(self, link, cache_dir):
        from rbd_local.gestures.config import load_config
        from rbd_local.gestures.model import GestureModel

        cfg = load_config()
        self.model = GestureModel.load(cfg["model"])
        self.mapping = cfg["gestures"]
        self.cfg = cfg
        self.link = link
        self.cache_dir = cache_dir
        self._sprites = None

    def sprites(self):
        """Hand sprites of the two real photos (loaded once)."""
        if self._sprites is None:
            from rbd_local.evaluation import load_sprites
            from rbd_local.testdata import fetch_hand_photos

            photos = fetch_hand_photos(self.cache_dir)
            self._sprites = load_sprites([photos["handSrc.jpg"], photos["handDst.jpg"]])
        return self._sprites

    def clip(self, gesture, seed):
        """Frames of one baseline real-photo clip of ``gesture``."""
        import numpy as np

        from rbd_local.gestures import realclips

        return realclips.make_clip(self.sprites(), gesture, realclips.BASELINE, np.random.default_rng(seed))[1]

    def teach(self, seed):
        """A visitor shows the new gesture five times; the app learns it (teach mode)."""
        import numpy as np

        from rbd_local.gestures.detector import HandDetector
        from rbd_local.gestures.realclips import track_clip
        from rbd_local.gestures.teach import extract_show

        gesture, trick = TAUGHT
        windows = []
        with HandDetector(model_complexity=self.cfg["model_complexity"]) as det:
            for i in range(5):
                frames = self.clip(gesture, seed + i)
                kps = track_clip(det, frames)
                w = extract_show(np.arange(len(frames)) / 30.0, kps, self.model.window_s, self.model.samples)
                if w is not None:
                    windows.append(w)
        t0 = time.monotonic()
        report = self.model.teach(gesture, trick, np.stack(windows))
        say("a visitor teaches %r -> %s from %d shows (learned in %.0f ms)"
            % (gesture, trick, report["shows"], 1000 * (time.monotonic() - t0)))

    def show(self, trick, seed):
        """Perform the gesture for ``trick``; returns the commands the app sent."""
        from rbd_local.gestures.pipeline import GesturePipeline

        sent = []

        def send(command):
            sent.append(command)
            self.link.send_gesture(command)

        gesture = TAUGHT[0] if trick == TAUGHT[1] else GESTURE_OF[trick]
        pipe = GesturePipeline(self.model, self.mapping, send=send, model_complexity=self.cfg["model_complexity"])
        try:
            for i, frame in enumerate(self.clip(gesture, seed)):
                pipe.process(i / 30.0, frame)
                time.sleep(1.0 / 60.0)
        finally:
            pipe.close()
        say("audience shows %s (MediaPipe on a real-photo clip) -> app sent %s" % (gesture, sent or "nothing"))
        return sent
