"""Recording, metrics and plots of a position-controller run (thesis Fig. 19 / 21 style). ROS-free.

A run is the ground-truth pose over time, the commanded velocities over time and the goals
in the order they were sent (with the time each was sent). Stored as JSON.
"""

import json
import math
from typing import Any, Dict, List, Sequence, Tuple


class RunLog:
    """Samples of one run; times in seconds from the start of the run."""

    def __init__(self, start: Tuple[float, float, float] = (0.0, 0.0, 0.0)) -> None:
        self.start = tuple(start)
        self.poses = []  # type: List[Tuple[float, float, float, float]]   # t, x, y, yaw
        self.cmds = []  # type: List[Tuple[float, float, float, float]]    # t, vx, vy, wz
        self.goals = []  # type: List[Tuple[float, float, float, float]]   # t_sent, x, y, yaw
        self.done = None  # type: Optional[float]
        self.label = ""

    def to_dict(self) -> Dict[str, Any]:
        """Plain-data form (for JSON)."""
        return {
            "label": self.label,
            "start": list(self.start),
            "poses": [list(p) for p in self.poses],
            "cmds": [list(c) for c in self.cmds],
            "goals": [list(g) for g in self.goals],
            "done": self.done,
        }

    @classmethod
    def from_dict(cls, data: Dict[str, Any]) -> "RunLog":
        """Inverse of to_dict; raises ValueError on malformed data."""
        try:
            log = cls(tuple(float(v) for v in data["start"]))
            log.poses = [tuple(float(v) for v in p) for p in data["poses"]]
            log.cmds = [tuple(float(v) for v in c) for c in data.get("cmds", [])]
            log.goals = [tuple(float(v) for v in g) for g in data["goals"]]
            log.done = None if data.get("done") is None else float(data["done"])
            log.label = str(data.get("label", ""))
        except (KeyError, TypeError, ValueError) as err:
            raise ValueError("malformed run log: %s" % err) from None
        if not log.poses or not log.goals:
            raise ValueError("run log needs poses and goals")
        return log

    def save(self, path: str) -> None:
        """Write the run as JSON."""
        with open(path, "w") as fh:
            json.dump(self.to_dict(), fh)

    @classmethod
    def load(cls, path: str) -> "RunLog":
        """Read a run written by save()."""
        with open(path) as fh:
            return cls.from_dict(json.load(fh))


def segment_distance(p: Sequence[float], a: Sequence[float], b: Sequence[float]) -> float:
    """Distance from point p to the segment a-b [m]."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    u = 0.0 if length2 == 0.0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2))
    return math.hypot(p[0] - a[0] - u * dx, p[1] - a[1] - u * dy)


def metrics(log: RunLog) -> Dict[str, float]:
    """Max deviation from the straight segments between goals, total time, final errors.

    A sample taken while goal i was active is compared with the segment from goal i-1
    (the start for i = 0) to goal i.
    """
    points = [log.start[:2]] + [g[1:3] for g in log.goals]
    max_dev = 0.0
    for t, x, y, _ in log.poses:
        index = 0
        for i, goal in enumerate(log.goals):
            if t >= goal[0]:
                index = i
        max_dev = max(max_dev, segment_distance((x, y), points[index], points[index + 1]))
    _, x, y, yaw = log.poses[-1]
    gx, gy, gyaw = log.goals[-1][1:]
    end = log.done if log.done is not None else log.poses[-1][0]
    return {
        "max_deviation_m": max_dev,
        "total_time_s": end - log.goals[0][0],
        "final_position_error_m": math.hypot(x - gx, y - gy),
        "final_yaw_error_deg": abs(math.degrees(math.atan2(math.sin(yaw - gyaw), math.cos(yaw - gyaw)))),
        "drift_from_start_m": math.hypot(x - log.start[0], y - log.start[1]),
    }


def unwrap(angles: Sequence[float]) -> List[float]:
    """Remove 2 pi jumps from a sequence of angles [rad]."""
    out = []  # type: List[float]
    for a in angles:
        if out:
            a = out[-1] + math.atan2(math.sin(a - out[-1]), math.cos(a - out[-1]))
        out.append(a)
    return out


def plot(log: RunLog, out_prefix: str, title: str = "") -> List[str]:
    """Write <out_prefix>_path.png (xy plane) and <out_prefix>_velocities.png; return the paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    title = title or log.label
    m = metrics(log)
    files = []

    fig, ax = plt.subplots(figsize=(6.0, 4.5))
    points = [log.start[:2]] + [g[1:3] for g in log.goals]
    ax.plot([p[0] for p in points], [p[1] for p in points], "--", color="0.6", label="desired path")
    ax.plot([p[1] for p in log.poses], [p[2] for p in log.poses], color="C0", label="robot (ground truth)")
    ax.plot([p[0] for p in points[1:]], [p[1] for p in points[1:]], "o", color="C3", label="goals")
    ax.plot([log.start[0]], [log.start[1]], "s", color="k", label="start")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    ax.set_title(
        "%s\nmax deviation %.3f m, final error %.3f m / %.1f deg"
        % (title, m["max_deviation_m"], m["final_position_error_m"], m["final_yaw_error_deg"]),
        fontsize=9,
    )
    fig.tight_layout()
    files.append(out_prefix + "_path.png")
    fig.savefig(files[-1], dpi=120)
    plt.close(fig)

    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7.0, 5.5), sharex=True)
    t = [c[0] for c in log.cmds]
    ax1.step(t, [c[1] for c in log.cmds], where="post", label="v_x [m/s]")
    ax1.step(t, [c[2] for c in log.cmds], where="post", label="v_y [m/s]")
    ax1.step(t, [c[3] for c in log.cmds], where="post", label="yaw rate [rad/s]")
    for goal in log.goals:
        ax1.axvline(goal[0], color="0.8", lw=0.8)
    ax1.set_ylabel("commanded velocity")
    ax1.grid(True, alpha=0.3)
    ax1.legend(loc="upper right", fontsize=8)
    ax1.set_title("%s: total %.1f s" % (title, m["total_time_s"]), fontsize=9)
    ax2.plot([p[0] for p in log.poses], [math.degrees(v) for v in unwrap([p[3] for p in log.poses])], color="C2")
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("yaw [deg]")
    ax2.grid(True, alpha=0.3)
    fig.tight_layout()
    files.append(out_prefix + "_velocities.png")
    fig.savefig(files[-1], dpi=120)
    plt.close(fig)
    return files
