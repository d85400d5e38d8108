"""Late clouds: when each simulated OS1 cloud is published after its capture. ROS-free.

A real OS1's cloud reaches rbd_lidar some time after the scan it shows: the driver assembles the
packets, a loaded host schedules the subscriber late, a network hop queues it. The simulated OS1
can reproduce that: every cloud keeps its capture stamp (as a real late cloud does) and is
published ``delay`` seconds after it; a seeded fraction ``late_fraction`` of the clouds waits
``late_delay`` seconds instead (the total delay of a late cloud, not an extra). A late cloud may
then be published after a younger one, as on a congested link.
"""

import heapq
import math
import random
from typing import Any, List, Optional, Tuple


class CloudDelay:
    """Holds captured clouds until they are due.

    Args:
        delay: delay of every cloud after its capture stamp [s], >= 0.
        late_fraction: fraction of the clouds delayed by ``late_delay`` instead, in [0, 1].
        late_delay: total delay of such a late cloud [s], >= 0.
        seed: seed of the draw that picks the late clouds (the same seed, the same late clouds).

    Raises:
        ValueError: a value out of range or not finite.
    """

    def __init__(self, delay: float = 0.0, late_fraction: float = 0.0, late_delay: float = 0.0, seed: int = 1) -> None:
        for name, value in (("cloud_delay", delay), ("late_fraction", late_fraction), ("late_delay", late_delay)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
                raise ValueError("%s must be a finite number >= 0, got %r" % (name, value))
        if late_fraction > 1.0:
            raise ValueError("late_fraction must be in [0, 1], got %r" % (late_fraction,))
        self.delay = float(delay)
        self.late_fraction = float(late_fraction)
        self.late_delay = float(late_delay)
        self._rng = random.Random(seed)
        self._pending: List[Tuple[float, int, Any]] = []  # heap of (due, push order, cloud)
        self._count = 0

    @property
    def enabled(self) -> bool:
        """Whether any cloud is held back at all (else the node publishes at once, as before)."""
        return self.delay > 0.0 or (self.late_fraction > 0.0 and self.late_delay > 0.0)

    def next_delay(self) -> float:
        """The delay of the next cloud [s] (one draw per cloud, so the sequence depends on the seed only)."""
        late = self._rng.random() < self.late_fraction
        return self.late_delay if late else self.delay

    def push(self, stamp: float, item: Any) -> float:
        """Holds ``item`` captured at ``stamp`` [s]; returns when it is due [s]."""
        due = float(stamp) + self.next_delay()
        heapq.heappush(self._pending, (due, self._count, item))
        self._count += 1
        return due

    def next_due(self) -> Optional[float]:
        """When the next held cloud is due [s]; None when none is held."""
        return self._pending[0][0] if self._pending else None

    def pop_due(self, now: float) -> List[Any]:
        """The held clouds due at ``now`` [s], earliest due first; they are no longer held."""
        out = []
        while self._pending and self._pending[0][0] <= now:
            out.append(heapq.heappop(self._pending)[2])
        return out

    def __len__(self) -> int:
        return len(self._pending)
