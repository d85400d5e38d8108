"""A reproducible crowd walking around the robot's trick area (ROS-free).

``crowd_people`` draws ``count`` people (named ``crowd0``, ``crowd1``, ...) from ``seed``: each
walks a loop or a there-and-back path of ``waypoints`` random points in the ring between
``inner_radius`` and ``outer_radius`` around ``center`` at a speed drawn from [``min_speed``,
``max_speed``] (at most 1.5 m/s) with a random phase. Every point *and every segment* of a path
keeps ``inner_radius`` from the centre, so the crowd walks around the trick area but never
through it. The same seed gives the same crowd.
"""

import math
import random

from rbd_sim.shapes import DEFAULT_REFLECTIVITY, Person, WorldError

#: Fastest walker a crowd may have [m/s] (issue 10: people walk at up to 1.5 m/s).
CROWD_MAX_SPEED = 1.5


def segment_distance(a: tuple, b: tuple, p: tuple) -> float:
    """Distance [m] from point p to the segment a-b (all (x, y))."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    ll = dx * dx + dy * dy
    f = 0.0 if ll <= 0.0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / ll))
    return math.hypot(a[0] + f * dx - p[0], a[1] + f * dy - p[1])


def crowd_people(
    count: int,
    seed: int,
    center: tuple = (0.0, 0.0),
    inner_radius: float = 1.5,
    outer_radius: float = 4.5,
    min_speed: float = 0.5,
    max_speed: float = CROWD_MAX_SPEED,
    waypoints: int = 4,
    min_radius: float = 0.18,
    max_radius: float = 0.27,
    height: float = 1.75,
) -> list:
    """Draw a reproducible crowd walking around ``center`` (see the module docstring).

    Args:
        count: Number of people (0..200).
        seed: Random seed; the same arguments give the same crowd.
        center: Centre of the area the crowd keeps out of [m].
        inner_radius: No path point or segment comes closer to the centre than this [m].
        outer_radius: No path point is farther than this [m].
        min_speed: Slowest walking speed [m/s].
        max_speed: Fastest walking speed [m/s], <= 1.5.
        waypoints: Points per path (>= 2).
        min_radius: Smallest body radius [m].
        max_radius: Largest body radius [m].
        height: Body height [m] (each person varies by +-0.2 m).

    Returns:
        The people, named crowd0 .. crowd<count-1>.

    Raises:
        WorldError: inconsistent arguments.
    """
    if not 0 <= count <= 200:
        raise WorldError("crowd: count must be in 0..200, got %r" % count)
    if not 0.0 < inner_radius < outer_radius:
        raise WorldError("crowd: need 0 < inner_radius < outer_radius (got %g, %g)" % (inner_radius, outer_radius))
    if outer_radius < 1.2 * inner_radius:
        raise WorldError("crowd: the ring is too narrow to walk in (outer_radius >= 1.2 * inner_radius)")
    if not 0.0 < min_speed <= max_speed <= CROWD_MAX_SPEED:
        raise WorldError(
            "crowd: need 0 < min_speed <= max_speed <= %g m/s (got %g, %g)" % (CROWD_MAX_SPEED, min_speed, max_speed)
        )
    if waypoints < 2 or waypoints > 20:
        raise WorldError("crowd: waypoints must be in 2..20, got %r" % waypoints)
    if not 0.05 <= min_radius <= max_radius <= 1.0:
        raise WorldError("crowd: need 0.05 <= min_radius <= max_radius <= 1.0 m")
    rng = random.Random(seed)
    cx, cy = float(center[0]), float(center[1])

    def point() -> tuple:
        # Uniform over the ring's area.
        r = math.sqrt(rng.uniform(inner_radius ** 2, outer_radius ** 2))
        a = rng.uniform(-math.pi, math.pi)
        return (cx + r * math.cos(a), cy + r * math.sin(a))

    def clear(a: tuple, b: tuple) -> bool:
        return segment_distance(a, b, (cx, cy)) >= inner_radius

    people = []
    for i in range(count):
        pts = [point()]
        while len(pts) < waypoints:
            for _ in range(500):
                p = point()
                if clear(pts[-1], p) and math.hypot(p[0] - pts[-1][0], p[1] - pts[-1][1]) > 0.5:
                    pts.append(p)
                    break
            else:
                break  # cannot extend (very narrow ring): walk what we have
        if len(pts) < 2:
            raise WorldError("crowd: could not draw a path for crowd%d; widen the ring" % i)
        mode = "loop" if len(pts) > 2 and clear(pts[-1], pts[0]) and rng.random() < 0.5 else "pingpong"
        speed = rng.uniform(min_speed, max_speed)
        person = Person(
            "crowd%d" % i,
            pts,
            speed,
            mode,
            rng.uniform(min_radius, max_radius),
            height + rng.uniform(-0.2, 0.2),
            0.0,
            DEFAULT_REFLECTIVITY["person"],
        )
        person.phase = rng.uniform(0.0, person.length / speed)
        people.append(person)
    return people
