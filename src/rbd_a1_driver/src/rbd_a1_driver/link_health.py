"""The A1 link's health for ``/diagnostics``: the verdict and the numbers, free of ROS.

The node (``nodes/rbd_a1_driver``) reads its gate and decoder once a second, under its lock, into
a :class:`LinkSnapshot`; :func:`link_verdict` says how healthy the link is (the first matching
cause wins: no usable HighState, no HighState, e-stop signal lost, remote e-stop, e-stop, no e-stop
signal yet) and :func:`link_values` lists the keys preflight and the tests read (the rbd_a1_driver
README, "the diagnostics contract"). :class:`RateMeter` turns the running counters into rates.
"""

from typing import List, Tuple

#: diagnostic_msgs/DiagnosticStatus levels.
OK, WARN, ERROR = 0, 1, 2
#: The status name (diagnostic_updater prefixes the node's name: ``rbd_a1_driver: A1 link``).
DIAG_NAME = "A1 link"
HARDWARE_ID = "unitree_a1"


class LinkSnapshot:
    """What the driver knows about its link at one moment (plain values, no ROS)."""

    def __init__(self, **fields: object) -> None:
        """Every field by keyword; missing ones take the defaults of :data:`LinkSnapshot.DEFAULTS`.

        Raises:
            ValueError: on an unknown field.
        """
        unknown = sorted(set(fields) - set(self.DEFAULTS))
        if unknown:
            raise ValueError("unknown link snapshot field(s): %s" % ", ".join(unknown))
        for key, value in self.DEFAULTS.items():
            setattr(self, key, fields.get(key, value))

    DEFAULTS = {
        "fresh": False,  # a HighState within the gate's timeout
        "wrong_recent": 0,  # packets of an unknown size since the last report
        "last_size": 0,  # size of the last HighState packet [B]
        "known_sizes": "",  # the sizes the decoder knows, as text
        "forced": "",  # ~sdk_layout when set
        "estop_lost": False,
        "remote": "off",  # the remote e-stop: off / released / engaged
        "remote_combo": "",
        "estop": False,
        "estop_missing": False,  # estop_required and no signal yet
        "lcm_url": "",
        "layout": "",
        "layout_source": "",
        "state_rate": 0.0,
        "cmd_rate": 0.0,
        "wrong_total": 0,
        "armed": False,
        "foot_force": "[0, 0, 0, 0]",
        "sent": 0,
        "received": 0,
        "rejected_states": 0,
        "rejected_cmds": 0,
        "mode": 0,
        "zero_reason": "",
    }


def link_verdict(s: LinkSnapshot) -> Tuple[int, str]:
    """(level, message) of the link: ERROR when the A1 is not heard, WARN while an e-stop holds it."""
    if not s.fresh and s.wrong_recent:
        return ERROR, "no usable HighState: %d packets of %s B, known sizes are %s%s: sending zero velocity" % (
            s.wrong_recent, s.last_size, s.known_sizes, " (~sdk_layout forces %s)" % s.forced if s.forced else "")
    if not s.fresh:
        return ERROR, "no HighState: sending zero velocity"
    if s.estop_lost:
        return ERROR, "e-stop signal lost: zero velocity"
    if s.remote == "engaged":
        return WARN, "remote e-stop engaged (%s): zero velocity until the operator releases" % s.remote_combo
    if s.estop:
        return WARN, "e-stop engaged: zero velocity"
    if s.estop_missing:
        return WARN, "no e-stop signal yet (estop_required): zero velocity"
    return OK, "ok"


def link_values(s: LinkSnapshot) -> List[Tuple[str, str]]:
    """The status's key/value pairs, in the contract's order, as text."""
    return [
        ("lcm_url", s.lcm_url),
        ("sdk_layout", s.layout or "unknown"),
        ("sdk_layout_source", s.layout_source),
        ("high_state_size", str(s.last_size or 0)),
        ("high_state_rate", "%.1f" % s.state_rate),
        ("high_cmd_rate", "%.1f" % s.cmd_rate),
        ("unknown_size_packets", str(s.wrong_total)),
        ("estop_gate_armed", "true" if s.armed else "false"),
        ("remote_estop", s.remote),
        ("foot_force", s.foot_force),
        ("high_cmd_sent", str(s.sent)),
        ("high_state_received", str(s.received)),
        ("high_state_rejected", str(s.rejected_states)),
        ("cmd_vel_rejected", str(s.rejected_cmds)),
        ("mode", str(s.mode)),
        ("zero_velocity_reason", s.zero_reason or ""),
    ]


class RateMeter:
    """Rates of the HighStates decoded and HighCmds sent between two reports, and new bad packets."""

    def __init__(self, now: float) -> None:
        """Start counting at ``now`` [s, monotonic] from zero counters."""
        self._mark = (now, 0, 0)
        self._wrong = 0

    def read(self, now: float, states: int, sent: int, wrong: int) -> Tuple[float, float, int]:
        """(HighState rate [Hz], HighCmd rate [Hz], unknown-size packets) since the last read."""
        t0, states0, sent0 = self._mark
        span = max(now - t0, 1e-3)
        self._mark = (now, states, sent)
        wrong_recent, self._wrong = wrong - self._wrong, wrong
        return (states - states0) / span, (sent - sent0) / span, wrong_recent
