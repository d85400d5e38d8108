"""Judging a stream: its rate, its age and whether its stamps are in this host's ROS time."""

from typing import Optional, Tuple

import numpy as np

from rbd_preflight.model import FAIL, PASS, Observation, Stream


def fmt_rate(stream: Stream) -> str:
    """``nothing received``, ``1 message`` or ``12.3 Hz``."""
    if stream.count == 0:
        return "nothing received"
    if stream.count == 1:
        return "1 message"
    return "%.1f Hz" % stream.rate()


def lag_problem(stream: Stream, max_lag: float, max_future: float) -> Optional[str]:
    """A text if the header stamps are not in this host's ROS time (too old or in the future)."""
    lags = stream.lags()
    if not lags:
        return None
    lag = float(np.median(lags))
    if lag < -max_future:
        return "stamps %.3f s in the future" % -lag
    if lag > max_lag:
        return "stamps %.3f s old on arrival" % lag
    return None


def rate_check(obs: Observation, key: str, topic: str, min_rate: float, max_age: float, max_lag: float,
                max_future: float, hint_silent: str, hint_slow: str, hint_stamps: str) -> Tuple[str, str, str]:
    """(status, value, hint) of a stream that must arrive at >= min_rate, fresh, stamped in ROS time."""
    s = obs.stream(key)
    if s.count == 0:
        return FAIL, "%s: nothing in %.1f s" % (topic, obs.duration), hint_silent
    rate = s.rate()
    age = s.age(obs.now)
    value = "%s, last %.2f s ago" % (fmt_rate(s), age)
    if rate < min_rate:
        return FAIL, value + " (need >= %.0f Hz)" % min_rate, hint_slow
    if age > max_age:
        return FAIL, value + " (stale after %.2f s)" % max_age, hint_silent
    problem = lag_problem(s, max_lag, max_future)
    if problem:
        return FAIL, value + ", " + problem, hint_stamps
    return PASS, value, ""


def last_diag(obs: Observation) -> Optional[dict]:
    """The A1 driver's last diagnostics status, if any."""
    return obs.a1_diag[-1] if obs.a1_diag else None


def diag_float(diag: dict, key: str) -> Optional[float]:
    """The number under ``key`` in a diagnostics status (None if missing or not a number)."""
    try:
        return float(diag["values"][key])
    except (KeyError, TypeError, ValueError):
        return None
