"""Tricks: named pose sequences, loaded from YAML and expanded around the robot's pose.

ROS-free. A trick is a list of steps; each step is relative to the robot's pose at the
time the path is requested: ``x``/``y`` are offsets in the robot's frame at that moment
[m], ``yaw`` is a heading change [rad]; ``roll``, ``pitch`` [rad] and ``body_height`` [m]
are the body attitude/height to hold at the goal (absolute, 0 = neutral). Every step has a
human-readable ``name`` that the GUI shows in its "next five moves" list.
"""

import math
from typing import Any, Dict, List, Mapping

from rbd_geometry.goal import Goal
from rbd_geometry.rotation import wrap_angle

STEP_KEYS = ("name", "x", "y", "yaw", "roll", "pitch", "body_height")
#: Body limits of the A1 (rbd_msgs/SetBodyPose comments): roll/pitch [rad], height [m].
ROLL_PITCH_LIMIT = 0.75
BODY_HEIGHT_MIN = -0.16
BODY_HEIGHT_MAX = 0.06
#: Largest translation one step may ask for [m]; tricks are small, on-the-spot moves.
MAX_STEP_OFFSET = 3.0


class TrickError(ValueError):
    """Raised when a tricks file or a request is invalid."""


class Step(Goal):
    """One step of a trick: a goal relative to the robot's pose at request time.

    ``x``/``y`` are offsets in the robot's frame [m], ``yaw`` a heading change [rad]; roll, pitch
    and body_height are absolute (as in :class:`rbd_geometry.goal.Goal`); ``name`` is required.
    """

    __slots__ = ()

    def __repr__(self) -> str:
        """Readable form for logs and test failures."""
        return "Step(%s)" % ", ".join("%s=%r" % (k, getattr(self, k)) for k in STEP_KEYS)


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TrickError("%s must be a number, got %r" % (where, value))
    value = float(value)
    if not math.isfinite(value):
        raise TrickError("%s must be finite, got %r" % (where, value))
    return value


def parse_step(raw: Any, where: str) -> Step:
    """Validate one step mapping and return it as a Step.

    Args:
        raw: the YAML mapping of the step.
        where: location for error messages, e.g. ``"tricks.walk[0]"``.

    Returns:
        The validated step.

    Raises:
        TrickError: on a missing name, unknown key, non-number or out-of-range value.
    """
    if not isinstance(raw, Mapping):
        raise TrickError("%s must be a mapping with a 'name', got %r" % (where, raw))
    unknown = sorted(set(raw) - set(STEP_KEYS))
    if unknown:
        raise TrickError("%s has unknown key(s) %s; allowed: %s" % (where, unknown, ", ".join(STEP_KEYS)))
    name = raw.get("name")
    if not isinstance(name, str) or not name.strip():
        raise TrickError("%s needs a non-empty string 'name'" % where)
    values = {k: _number(raw.get(k, 0.0), "%s.%s" % (where, k)) for k in STEP_KEYS[1:]}
    for key in ("x", "y"):
        if abs(values[key]) > MAX_STEP_OFFSET:
            raise TrickError("%s.%s = %g m exceeds +-%g m" % (where, key, values[key], MAX_STEP_OFFSET))
    for key in ("roll", "pitch"):
        if abs(values[key]) > ROLL_PITCH_LIMIT:
            raise TrickError(
                "%s.%s = %g rad exceeds the A1 limit +-%g rad" % (where, key, values[key], ROLL_PITCH_LIMIT)
            )
    if not BODY_HEIGHT_MIN <= values["body_height"] <= BODY_HEIGHT_MAX:
        raise TrickError(
            "%s.body_height = %g m outside the A1 range [%g, %g] m"
            % (where, values["body_height"], BODY_HEIGHT_MIN, BODY_HEIGHT_MAX)
        )
    return Step(name=name.strip(), **values)


def parse_tricks(data: Any) -> Dict[str, List[Step]]:
    """Validate the content of a tricks YAML file.

    Args:
        data: the parsed YAML: ``{"tricks": {name: [step, ...], ...}}`` or the inner mapping.

    Returns:
        Trick name -> list of steps.

    Raises:
        TrickError: when anything is missing or invalid (fail fast at startup).
    """
    if isinstance(data, Mapping) and "tricks" in data:
        data = data["tricks"]
    if not isinstance(data, Mapping) or not data:
        raise TrickError("tricks must be a non-empty mapping of trick name -> list of steps")
    tricks = {}
    for name, steps in data.items():
        if not isinstance(name, str) or not name.strip() or name != name.strip():
            raise TrickError("trick names must be non-empty strings without surrounding spaces, got %r" % (name,))
        if not isinstance(steps, list) or not steps:
            raise TrickError("tricks.%s must be a non-empty list of steps" % name)
        tricks[name] = [parse_step(raw, "tricks.%s[%d]" % (name, i)) for i, raw in enumerate(steps)]
    return tricks


def expand(steps: List[Step], x: float, y: float, yaw: float) -> List[Goal]:
    """Turn relative steps into absolute goals around the robot pose (x, y, yaw).

    Args:
        steps: the trick's steps.
        x: robot x at request time [m].
        y: robot y at request time [m].
        yaw: robot heading at request time [rad].

    Returns:
        One absolute goal per step, in order.

    Raises:
        TrickError: if the robot pose is not finite.
    """
    for value, label in ((x, "x"), (y, "y"), (yaw, "yaw")):
        if not math.isfinite(value):
            raise TrickError("robot pose %s is not finite (%r)" % (label, value))
    c, s = math.cos(yaw), math.sin(yaw)
    goals = []
    for step in steps:
        goals.append(
            Goal(
                x + c * step.x - s * step.y,
                y + s * step.x + c * step.y,
                wrap_angle(yaw + step.yaw),
                roll=step.roll,
                pitch=step.pitch,
                body_height=step.body_height,
                name=step.name,
            )
        )
    return goals
