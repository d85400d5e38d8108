"""The preflight table as text, with the mounts in use."""

import math
from typing import List, Optional, Sequence, Tuple

from rbd_geometry.rotation import quat_to_rpy
from rbd_preflight.model import FAIL, PASS, SKIP, Observation, Row, passed


def format_mount(transform: object) -> str:
    """``xyz (-0.080, 0.000, 0.070) m, rpy (0.0, 0.0, 0.0) deg``."""
    (x, y, z), q = transform
    r, p, yw = (math.degrees(a) for a in quat_to_rpy(q))
    return "xyz (%.3f, %.3f, %.3f) m, rpy (%.1f, %.1f, %.1f) deg" % (x, y, z, r, p, yw)


def mounts_in_use(obs: Observation) -> List[Tuple[str, str]]:
    """(frame, mount text) of the sensor frames and the zone origin, as TF has them."""
    out = []
    for frame in (obs.lidar_frame, obs.zed2_frame, "collision_zone"):
        t = obs.frames.get(frame)
        out.append((frame, format_mount(t) if t is not None and not isinstance(t, str) else "missing"))
    return out


def render(rows: Sequence[Row], obs: Optional[Observation] = None, colour: bool = False) -> str:
    """The table as text: one line per check (status, check, measured value, what to do on FAIL)."""
    width = max(len(r.name) for r in rows) if rows else 10
    paint = {PASS: "\033[32m%s\033[0m", FAIL: "\033[1;31m%s\033[0m", SKIP: "\033[33m%s\033[0m"}
    lines = []
    for r in rows:
        status = paint[r.status] % r.status if colour else r.status
        line = "%s  %-*s  %s" % (status, width, r.name, r.value)
        if r.status == FAIL and r.hint:
            line += "  -> %s" % r.hint
        lines.append(line)
    n_fail = sum(1 for r in rows if r.status == FAIL)
    n_skip = sum(1 for r in rows if r.status == SKIP)
    if obs is not None:
        lines.append("")
        lines.append("Mounts in use%s:" % (" (%s)" % obs.mounts_file if obs.mounts_file else ""))
        for frame, text in mounts_in_use(obs):
            lines.append("  %s -> %-20s %s" % (obs.base_frame, frame, text))
    lines.append("")
    lines.append("preflight: %s (%d checks, %d failed, %d skipped)" % (
        "READY" if passed(rows) else "NOT READY", len(rows), n_fail, n_skip))
    return "\n".join(lines)
