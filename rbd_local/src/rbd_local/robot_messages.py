"""The robot's messages as the laptop app uses them: tricks and preflight reports (no roslibpy).

Each function takes a message (or parameter value) as rosbridge sends it, as plain JSON
values, checks its shape and returns what the app shows; a malformed one raises ValueError.
"""

from rbd_local.robot_names import PREFLIGHT_STATUSES, TRICKS_PARAM


def tricks_from_param(value: object) -> dict:
    """The trick names and their steps' names from the value of ``/rbd_navigation/tricks``.

    Args:
        value: the parameter as rosapi returns it: {trick: [{"name": ..., "x": ..., ...}]}.

    Returns:
        {trick: [step name, ...]} in the parameter's order.

    Raises:
        ValueError: when the value does not have that shape.
    """
    if not isinstance(value, dict) or not value:
        raise ValueError("%s is not a mapping of tricks: %r" % (TRICKS_PARAM, value))
    out = {}
    for name, steps in value.items():
        if not isinstance(steps, list) or not steps:
            raise ValueError("%s/%s is not a list of steps" % (TRICKS_PARAM, name))
        names = []
        for i, step in enumerate(steps):
            if not isinstance(step, dict) or not isinstance(step.get("name"), str):
                raise ValueError("%s/%s[%d] has no name" % (TRICKS_PARAM, name, i))
            names.append(step["name"])
        out[str(name)] = names
    return out


def _stamp_seconds(stamp: object) -> float:
    if not isinstance(stamp, dict):
        raise ValueError("header.stamp is not a time: %r" % (stamp,))
    secs, nsecs = stamp.get("secs"), stamp.get("nsecs", 0)
    if not isinstance(secs, int) or not isinstance(nsecs, int):
        raise ValueError("header.stamp is not a time: %r" % (stamp,))
    return secs + nsecs * 1e-9


def preflight_report_from_msg(msg: object) -> dict:
    """A preflight report as the GUI shows it, from an rbd_msgs/PreflightReport message dict.

    Args:
        msg: the message as rosbridge sends it (``header``, ``ready``, ``duration``,
            ``checks``: [{``key``, ``name``, ``status``, ``value``, ``hint``}], ``mounts``,
            ``mounts_file``).

    Returns:
        {"ready": bool, "stamp": float (POSIX seconds, end of the observation; 0 if unset),
        "duration": float [s], "checks": [{"key", "name", "status", "value", "hint"}] in the
        robot's order, "mounts": [str], "mounts_file": str}.

    Raises:
        ValueError: when the message does not have that shape or a status is not PASS/FAIL/SKIP.
    """
    if not isinstance(msg, dict):
        raise ValueError("preflight report is not a message: %r" % (msg,))
    header = msg.get("header")
    stamp = _stamp_seconds(header.get("stamp") if isinstance(header, dict) else None)
    rows = msg.get("checks")
    if not isinstance(rows, list) or not isinstance(msg.get("ready"), bool):
        raise ValueError("preflight report without ready/checks: %r" % (msg,))
    checks = []
    for i, row in enumerate(rows):
        if not isinstance(row, dict):
            raise ValueError("preflight check %d is not a message" % i)
        fields = {k: row.get(k, "") for k in ("key", "name", "status", "value", "hint")}
        if not all(isinstance(v, str) for v in fields.values()) or fields["status"] not in PREFLIGHT_STATUSES:
            raise ValueError("preflight check %d is malformed: %r" % (i, row))
        checks.append(fields)
    mounts = msg.get("mounts", [])
    try:
        duration = float(msg.get("duration", 0.0))
    except (TypeError, ValueError):
        duration = None
    if duration is None or not isinstance(mounts, list):
        raise ValueError("preflight report has a bad duration or mounts: %r" % (msg,))
    return {"ready": msg["ready"], "stamp": stamp, "duration": duration, "checks": checks,
            "mounts": [str(m) for m in mounts], "mounts_file": str(msg.get("mounts_file", ""))}
