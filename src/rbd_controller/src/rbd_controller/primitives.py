"""Motion primitives of the SE(2) lattice (:mod:`rbd_controller.lattice`). ROS-free."""

import math
from typing import List, Tuple

import numpy as np

#: (dx, dy, dbin, cost [s], samples M x 3 relative (dx, dy, heading), curvature [1/m]).
Primitive = Tuple[float, float, int, float, np.ndarray, float]


def primitives(step: float, headings: int, speed: float, turn_rate: float,
               spot_penalty: float) -> List[List[Primitive]]:
    """Per heading bin, its motions: forward arcs of step turning 0, +-1 or +-2 bins, turns on the spot by one bin.

    Args:
        step: length of a forward motion [m].
        headings: heading bins.
        speed: walking speed [m/s] (the cost is time).
        turn_rate: the follower's yaw-rate limit at that speed [rad/s].
        spot_penalty: added to a turn on the spot's time [s].

    Returns:
        Per bin a list of primitives; on-the-spot turns have dx = dy = 0 and an infinite curvature.
    """
    out = []
    width = 2.0 * math.pi / headings
    for k in range(headings):
        th = k * width
        prims = []  # type: List[Primitive]
        for dk in (-2, -1, 0, 1, 2):
            turn = dk * width
            # Samples <= 0.02 m and <= 0.01 rad apart (the exact check's EXACT_MARGIN covers what lies between).
            n = max(2, int(math.ceil(step / 0.02)), int(math.ceil(abs(turn) / 0.01)))
            s = np.arange(1, n + 1) / n * step
            if dk == 0:
                xs, ys, hs = s * math.cos(th), s * math.sin(th), np.full(n, th)
            else:
                kappa = turn / step
                hs = th + kappa * s
                xs = (np.sin(hs) - math.sin(th)) / kappa
                ys = (math.cos(th) - np.cos(hs)) / kappa
            cost = max(step / speed, abs(turn) / turn_rate) + 0.05 * abs(dk)
            prims.append((float(xs[-1]), float(ys[-1]), dk, cost, np.stack([xs, ys, hs], axis=1), turn / step))
        for dk in (-1, 1):
            m = max(2, int(math.ceil(width / 0.01)))
            hs = th + dk * width * np.arange(1, m + 1) / m
            samples = np.stack([np.zeros(m), np.zeros(m), hs], axis=1)
            prims.append((0.0, 0.0, dk, width / turn_rate + spot_penalty, samples, math.inf))
        out.append(prims)
    return out
