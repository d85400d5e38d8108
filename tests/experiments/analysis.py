"""ROS-free measurement maths of the thesis experiments (step metrics, zone geometry, search).

Everything here works on plain samples so it can be unit-tested without a simulator.
"""

import math
from typing import Callable, Dict, List, Optional, Sequence, Tuple


def step_metrics(samples: Sequence[Tuple[float, float]], t_step: float, t_end: float, amplitude: float) -> Dict:
    """Dead time, 10-90 % rise time, overshoot and steady-state error of a velocity step.

    Args:
        samples: (time [s], measured output velocity) in command units, any order.
        t_step: time the step command started [s].
        t_end: time the step command ended [s].
        amplitude: commanded step (non-zero).

    Returns:
        dead_time_s (first sample >= 10 % minus t_step), rise_time_s (10 % -> 90 %),
        overshoot_pct (peak above the amplitude, >= 0), steady_state_error_pct (mean of the last
        40 % of the step vs the amplitude). Values are None when the output never got there.
    """
    if amplitude == 0.0:
        raise ValueError("step amplitude must be non-zero")
    if t_end <= t_step:
        raise ValueError("step must end after it starts")
    sign = 1.0 if amplitude > 0 else -1.0
    a = abs(amplitude)
    during = sorted((t, sign * v) for t, v in samples if t_step <= t <= t_end)
    if not during:
        raise ValueError("no samples during the step")
    t10 = next((t for t, v in during if v >= 0.1 * a), None)
    t90 = next((t for t, v in during if v >= 0.9 * a), None)
    tail = [v for t, v in during if t >= t_end - 0.4 * (t_end - t_step)]
    peak = max(v for _, v in during)
    mean_tail = sum(tail) / len(tail) if tail else float("nan")
    return {
        "dead_time_s": None if t10 is None else t10 - t_step,
        "rise_time_s": None if (t10 is None or t90 is None) else t90 - t10,
        "overshoot_pct": max(0.0, (peak - a) / a * 100.0),
        "steady_state_error_pct": abs(mean_tail - a) / a * 100.0,
    }


def ramp_slope(samples: Sequence[Tuple[float, float]]) -> float:
    """Least-squares slope of (t, value) samples (the integrating behaviour of Fig. 18)."""
    n = len(samples)
    if n < 2:
        raise ValueError("need at least two samples")
    mt = sum(t for t, _ in samples) / n
    mv = sum(v for _, v in samples) / n
    den = sum((t - mt) ** 2 for t, _ in samples)
    if den == 0.0:
        raise ValueError("samples need distinct times")
    return sum((t - mt) * (v - mv) for t, v in samples) / den


def rect_distance(px: float, py: float, front: float, back: float, left: float, right: float) -> float:
    """Distance [m] from a point (sensor frame, x forward, y left) to the zone rectangle; 0 inside."""
    dx = max(px - front, -back - px, 0.0)
    dy = max(py - left, -right - py, 0.0)
    return math.hypot(dx, dy)


def expected_trigger_distance(angle: float, radius: float, zone: Sequence[float]) -> float:
    """Centre distance at which a cylinder on a ray from the LiDAR first touches the zone.

    Args:
        angle: ray direction in the sensor frame [rad] (0 = ahead, pi/2 = left).
        radius: cylinder radius [m].
        zone: (front, back, left, right) perpendicular distances [m].

    Returns:
        Distance [m] of the cylinder axis from the LiDAR along the ray.
    """
    front, back, left, right = zone
    c, s = math.cos(angle), math.sin(angle)
    lo, hi = 0.0, 10.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if rect_distance(mid * c, mid * s, front, back, left, right) <= radius:
            lo = mid
        else:
            hi = mid
    return lo


def find_flip(probe: Callable[[float], bool], near: float, far: float, resolution: float) -> Optional[float]:
    """Largest distance in [near, far] at which probe(distance) is True (bisection).

    probe must be True near and False far (monotonic); returns None when it is not.

    Args:
        probe: True when the target at that distance trips the zone.
        near: a distance that must trip [m].
        far: a distance that must not trip [m].
        resolution: stop when the bracket is narrower [m].

    Returns:
        The midpoint of the final bracket [m] or None when the bracket was not valid.
    """
    if probe(far) or not probe(near):
        return None
    while far - near > resolution:
        mid = 0.5 * (near + far)
        if probe(mid):
            near = mid
        else:
            far = mid
    return 0.5 * (near + far)


def lowest_true(probe: Callable[[float], bool], low: float, high: float, resolution: float) -> Optional[float]:
    """Smallest value in [low, high] at which probe(value) is True (bisection; probe grows monotonic).

    Args:
        probe: e.g. True when an obstacle of that height trips the zone.
        low: a value that must be False.
        high: a value that must be True.
        resolution: stop when the bracket is narrower.

    Returns:
        The upper end of the final bracket (a value seen True), or None when probe(high) is False
        or probe(low) is True.
    """
    if not probe(high) or probe(low):
        return None
    while high - low > resolution:
        mid = 0.5 * (low + high)
        if probe(mid):
            high = mid
        else:
            low = mid
    return high


def zone_outline(zone: Sequence[float]) -> List[Tuple[float, float]]:
    """Closed polygon of the zone rectangle in the sensor frame (for plots)."""
    front, back, left, right = zone
    return [(front, left), (-back, left), (-back, -right), (front, -right), (front, left)]


def unwrap(angles: Sequence[float]) -> List[float]:
    """Continuous angle sequence [rad]."""
    out = []
    for a in angles:
        if out:
            a = out[-1] + math.atan2(math.sin(a - out[-1]), math.cos(a - out[-1]))
        out.append(a)
    return out
