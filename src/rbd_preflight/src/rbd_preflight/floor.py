"""The floor the LiDAR sees: a RANSAC plane fit and its comparison with the feet (or body height)."""

import math
from typing import Optional, Tuple

import numpy as np

from rbd_preflight.facts import NOMINAL_BODY_HEIGHT
from rbd_preflight.model import FAIL, PASS, Limits


def fit_plane(points: np.ndarray, threshold: float = 0.03, iterations: int = 150,
              seed: int = 0) -> Optional[Tuple[np.ndarray, float, int]]:
    """Dominant plane of ``points`` (N x 3): RANSAC, then a least-squares refit on its inliers.

    Returns:
        (unit normal with z >= 0, d, inlier count) for the plane ``n . p + d = 0``, or None with
        fewer than 3 points.
    """
    pts = np.asarray(points, dtype=float)
    if pts.shape[0] < 3:
        return None
    rng = np.random.RandomState(seed)
    best, best_count = None, -1
    for _ in range(iterations):
        a, b, c = pts[rng.choice(pts.shape[0], 3, replace=False)]
        n = np.cross(b - a, c - a)
        norm = np.linalg.norm(n)
        if norm < 1e-9:
            continue
        n = n / norm
        count = int(np.count_nonzero(np.abs(pts.dot(n) - n.dot(a)) < threshold))
        if count > best_count:
            best, best_count = (n, -n.dot(a)), count
    if best is None:
        return None
    n, d = best
    inliers = pts[np.abs(pts.dot(n) + d) < threshold]
    centre = inliers.mean(axis=0)
    # the smallest singular vector of the centred inliers is the refitted normal
    n = np.linalg.svd(inliers - centre, full_matrices=False)[2][-1]
    if n[2] < 0:
        n = -n
    d = -float(n.dot(centre))
    return n, d, int(np.count_nonzero(np.abs(pts.dot(n) + d) < threshold))


def floor_check(points_base: np.ndarray, contacts: Optional[np.ndarray], limits: Limits,
                nominal_height: float = NOMINAL_BODY_HEIGHT) -> Tuple[str, str, str, dict]:
    """The floor the LiDAR sees against where the feet (or the nominal body height) put it.

    Args:
        points_base: the cloud in the body frame (N x 3) [m].
        contacts: the feet's floor contact points in the body frame (K x 3), or None: then the
            floor is expected level at ``-nominal_height``.
        limits: ``floor_tolerance``, ``floor_max_tilt_deg``, ``floor_min_points``.
        nominal_height: body height without foot frames [m].

    Returns:
        (status, value, hint, numbers): numbers has ``offset`` (how far the LiDAR's floor lies
        above the expected one [m]; a mount z too high by d gives +d), ``tilt_deg`` and ``inliers``.
    """
    pts = np.asarray(points_base, dtype=float).reshape(-1, 3)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if contacts is not None and len(contacts) >= 3:
        c = np.asarray(contacts, dtype=float)
        centre = c.mean(axis=0)
        n_exp = np.linalg.svd(c - centre, full_matrices=False)[2][-1]
        if n_exp[2] < 0:
            n_exp = -n_exp
        d_exp = -float(n_exp.dot(centre))
        source = "feet"
    else:
        n_exp, d_exp, source = np.array([0.0, 0.0, 1.0]), nominal_height, "nominal %.2f m" % nominal_height
    # candidates: 0.5-5 m around the body, within 0.3 m of the expected floor
    horizontal = np.hypot(pts[:, 0], pts[:, 1])
    near = np.abs(pts.dot(n_exp) + d_exp) < 0.3
    cand = pts[near & (horizontal > 0.5) & (horizontal < 5.0)]
    if cand.shape[0] > 6000:
        cand = cand[np.random.RandomState(1).choice(cand.shape[0], 6000, replace=False)]
    numbers = {"offset": None, "tilt_deg": None, "inliers": 0, "expected": source}
    fit = fit_plane(cand) if cand.shape[0] >= 3 else None
    if fit is None or fit[2] < limits.floor_min_points:
        return (FAIL, "no floor in the cloud (%d candidate points within 0.3 m of the expected floor, %s)"
                % (cand.shape[0], source),
                "the LiDAR must see the floor around the robot (standing on a level floor, no cover); "
                "or the os_sensor mount is off by more than 0.3 m", numbers)
    n, d, inliers = fit
    # height of the expected floor's points above the LiDAR's floor, the other way round
    ref = np.asarray(contacts, dtype=float) if source == "feet" else np.array([[0.0, 0.0, -nominal_height]])
    offset = float(-np.mean(ref.dot(n) + d))
    tilt = math.degrees(math.acos(max(-1.0, min(1.0, float(n.dot(n_exp))))))
    numbers.update(offset=offset, tilt_deg=tilt, inliers=inliers)
    value = "floor %+.3f m from the expected one (%s), tilt %.1f deg, %d points" % (offset, source, tilt, inliers)
    if abs(offset) > limits.floor_tolerance:
        where = "high" if offset > 0 else "low"
        return (FAIL, value,
                "the LiDAR's floor is %.0f mm too %s: the os_sensor z in the mounts file is %.0f mm too %s "
                "(or the body height is off); measure the mount again (rbd_description README, Mounts)"
                % (abs(offset) * 1000, where, abs(offset) * 1000, where), numbers)
    if tilt > limits.floor_max_tilt_deg:
        return (FAIL, value, "the LiDAR's floor is tilted: check the os_sensor roll/pitch in the mounts file", numbers)
    return PASS, value, "", numbers
