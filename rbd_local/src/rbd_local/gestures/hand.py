"""Hand model shared by the detector, the synthetic generator and the overlay.

MediaPipe Hands numbers its 21 key points wrist first, then four per finger from the base
to the tip (thumb, index, middle, ring, pinky). Coordinates used throughout this package are
normalised image coordinates: x to the right and y downwards in [0, 1], z relative depth.
"""

import numpy as np

NUM_LANDMARKS = 21
WRIST = 0
MIDDLE_MCP = 9
FINGER_TIPS = (4, 8, 12, 16, 20)
PALM = (0, 5, 9, 13, 17)

# Skeleton edges drawn by the overlay (palm outline plus the five finger chains).
HAND_CONNECTIONS = (
    (0, 1), (1, 2), (2, 3), (3, 4),
    (0, 5), (5, 6), (6, 7), (7, 8),
    (5, 9), (9, 10), (10, 11), (11, 12),
    (9, 13), (13, 14), (14, 15), (15, 16),
    (13, 17), (0, 17), (17, 18), (18, 19), (19, 20),
)  # fmt: skip

# An open right hand seen palm-on, fingers up, in "hand units": wrist at the origin and the
# middle finger's base joint one unit above it (image y grows downwards).
OPEN_HAND = np.array(
    [
        (0.00, 0.00),
        (-0.35, -0.25), (-0.60, -0.50), (-0.80, -0.75), (-0.95, -0.95),
        (-0.30, -1.00), (-0.35, -1.40), (-0.37, -1.65), (-0.38, -1.90),
        (0.00, -1.00), (0.00, -1.45), (0.00, -1.72), (0.00, -1.98),
        (0.25, -0.95), (0.28, -1.35), (0.30, -1.60), (0.31, -1.82),
        (0.45, -0.85), (0.52, -1.15), (0.56, -1.35), (0.58, -1.52),
    ],
    dtype=np.float64,
)  # fmt: skip


def hand_shape(curl: np.ndarray) -> np.ndarray:
    """Return hand templates with each finger curled by the given amount.

    Args:
        curl: (5,) or (N, 5) values in [0, 1] (thumb..pinky); 0 is straight, 1 fully curled.

    Returns:
        (21, 2) or (N, 21, 2) array in hand units.
    """
    curl = np.clip(np.asarray(curl, dtype=np.float64), 0.0, 1.0)
    if curl.shape[-1:] != (5,) or curl.ndim > 2:
        raise ValueError("curl needs five values per hand, got shape %s" % (curl.shape,))
    single = curl.ndim == 1
    curl = np.atleast_2d(curl)
    shape = np.repeat(OPEN_HAND[None], len(curl), axis=0)
    for finger in range(5):
        base = 1 + 4 * finger
        mcp = OPEN_HAND[base]
        c = curl[:, finger, None]
        for joint in range(1, 4):
            p = OPEN_HAND[base + joint]
            # A curled joint folds back towards the palm centre.
            folded = mcp + (p - mcp) * 0.3 + (np.array([0.0, -0.5]) - mcp) * 0.25 * joint
            shape[:, base + joint] = (1.0 - c) * p + c * folded
    return shape[0] if single else shape
