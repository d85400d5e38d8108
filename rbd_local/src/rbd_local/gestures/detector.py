"""MediaPipe Hands wrapper: an image in, 21 key points in pixels out."""

from __future__ import annotations

import numpy as np

from rbd_local.gestures.hand import NUM_LANDMARKS


class HandDetector:
    """Finds up to ``max_hands`` hands per frame with MediaPipe Hands (the models of the 0.10.21 wheel).

    Two hands by default: a visitor's second, still hand (at the side, near the face) must not
    hide the gesturing one (issue 26); the recognizer follows the hand that performs.
    """

    def __init__(
        self,
        static_image: bool = False,
        model_complexity: int = 1,
        min_detection_confidence: float = 0.5,
        min_tracking_confidence: float = 0.5,
        enhance_dark: bool = True,
        dark_level: float = 40.0,
        max_hands: int = 2,
    ) -> None:
        """Load the MediaPipe hand models.

        Args:
            static_image: detect afresh in every frame (photos) instead of tracking (video).
            model_complexity: 0 (lite, faster) or 1 (full).
            min_detection_confidence: palm-detection threshold in [0, 1].
            min_tracking_confidence: landmark-tracking threshold in [0, 1].
            enhance_dark: brighten dark frames before detection (see :func:`enhance_dark`).
            dark_level: a frame whose mean grey level is below this counts as dark [0..255].
            max_hands: most hands reported per frame (1 or 2).

        Raises:
            ValueError: on out-of-range arguments.
        """
        if model_complexity not in (0, 1):
            raise ValueError("model_complexity must be 0 or 1, got %r" % model_complexity)
        for name, value in (("min_detection_confidence", min_detection_confidence),
                            ("min_tracking_confidence", min_tracking_confidence)):
            if not 0.0 <= value <= 1.0:
                raise ValueError("%s must be in [0, 1], got %r" % (name, value))
        if int(max_hands) not in (1, 2):
            raise ValueError("max_hands must be 1 or 2, got %r" % max_hands)
        self.max_hands = int(max_hands)
        self.enhance_dark = bool(enhance_dark)
        self.dark_level = float(dark_level)
        self.enhanced_frames = 0
        import mediapipe as mp  # heavy import, deferred until a detector is needed

        self._hands = mp.solutions.hands.Hands(
            static_image_mode=static_image,
            max_num_hands=self.max_hands,
            model_complexity=model_complexity,
            min_detection_confidence=min_detection_confidence,
            min_tracking_confidence=min_tracking_confidence,
        )

    def detect(self, image_bgr: np.ndarray) -> tuple | None:
        """Find a hand in one BGR image (the first MediaPipe reports; see :meth:`detect_hands`).

        Args:
            image_bgr: (H, W, 3) uint8 image as OpenCV delivers it.

        Returns:
            ((21, 3) key points in pixels — x, y, and z scaled like x — , handedness score),
            or None when no hand is found.

        Raises:
            ValueError: if the image is not an (H, W, 3) uint8 array.
        """
        hands = self.detect_hands(image_bgr)
        return hands[0] if hands else None

    def detect_hands(self, image_bgr: np.ndarray) -> list:
        """Find every hand (up to ``max_hands``) in one BGR image.

        Args:
            image_bgr: (H, W, 3) uint8 image as OpenCV delivers it.

        Returns:
            A list of ((21, 3) key points in pixels, handedness score), in MediaPipe's order
            (not a fixed one: the recognizer follows hands by position); empty without a hand.

        Raises:
            ValueError: if the image is not an (H, W, 3) uint8 array.
        """
        import cv2

        img = np.asarray(image_bgr)
        if img.ndim != 3 or img.shape[2] != 3 or img.dtype != np.uint8 or img.shape[0] < 8 or img.shape[1] < 8:
            raise ValueError("expected an (H, W, 3) uint8 BGR image, got %s %s" % (img.shape, img.dtype))
        if self.enhance_dark and float(img[::8, ::8].mean()) < self.dark_level:
            img = enhance_dark(img)
            self.enhanced_frames += 1
        rgb = cv2.cvtColor(img, cv2.COLOR_BGR2RGB)
        rgb.flags.writeable = False
        result = self._hands.process(rgb)
        if not result.multi_hand_landmarks:
            return []
        h, w = img.shape[:2]
        out = []
        for i, hand in enumerate(result.multi_hand_landmarks):
            pts = np.array([(p.x * w, p.y * h, p.z * w) for p in hand.landmark], dtype=np.float64)
            if pts.shape != (NUM_LANDMARKS, 3):
                continue
            handed = result.multi_handedness
            score = float(handed[i].classification[0].score) if handed and i < len(handed) else 1.0
            out.append((pts, score))
        return out

    def close(self) -> None:
        """Release the MediaPipe graph."""
        self._hands.close()

    def __enter__(self) -> HandDetector:
        """Context-manager entry."""
        return self

    def __exit__(self, *exc: object) -> None:
        """Context-manager exit: close."""
        self.close()


#: Mean grey level a dark frame is lifted to by :func:`enhance_dark` [0..255].
DARK_TARGET_GREY = 100.0


def enhance_dark(image_bgr: np.ndarray, target_grey: float = DARK_TARGET_GREY) -> np.ndarray:
    """Brighten a dark, noisy frame for the hand detector.

    The frame is smoothed (5 x 5 Gaussian, against sensor noise) and lifted with the gamma
    curve ``v ** e`` (v in [0, 1], e <= 1, one lookup table for all three channels) that
    takes a pixel at the frame's mean grey level to ``target_grey``; the order of grey levels
    is kept.

    In a very dark frame the palm detector scores the hand below its threshold unless the
    frame is lifted this far: on the evaluation clips (README, "Robustness") the gamma lift
    finds the hand in nearly every frame of the darkest condition, where the former
    enhancement (CLAHE 1.5 on the smoothed Lab lightness, 2 x 2 tiles) missed the first
    0.5-0.9 s of some clips.

    Args:
        image_bgr: (H, W, 3) uint8 image.
        target_grey: mean grey level of the result [0..255] (a brighter frame is only smoothed).

    Returns:
        The enhanced image (a new array).

    Raises:
        ValueError: if ``target_grey`` is not in (0, 255].
    """
    import cv2

    if not 0.0 < target_grey <= 255.0:
        raise ValueError("target_grey must be in (0, 255], got %r" % (target_grey,))
    smooth = cv2.GaussianBlur(image_bgr, (5, 5), 0)
    mean = min(max(float(smooth[::8, ::8].mean()), 1.0), 254.0) / 255.0
    exponent = min(1.0, np.log(float(target_grey) / 255.0) / np.log(mean))
    lut = np.clip(np.rint(255.0 * (np.arange(256) / 255.0) ** exponent), 0, 255).astype(np.uint8)
    return cv2.LUT(smooth, lut)
