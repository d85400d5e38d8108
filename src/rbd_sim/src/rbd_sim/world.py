"""Simulated world: static geometry, people on scripted paths, obstacles placed at run time.

ROS-free. A world file is YAML (see ``worlds/lab.yaml``)::

    name: lab
    floor: {z: 0.0}                      # optional, default z 0
    ceiling: {z: 3.0}                    # optional, no ceiling when absent
    walls:   [{from: [x, y], to: [x, y], thickness: 0.1, height: 2.5}]
    boxes:   [{name: crate, center: [x, y], size: [lx, ly, lz], yaw: 0.0, z: 0.0}]
    tables:  [{name: t1, center: [x, y], size: [lx, ly], height: 0.75, yaw: 0.0}]
    cylinders: [{name: pillar, center: [x, y], radius: 0.2, height: 2.5}]
    people:  [{name: p1, path: [[x, y], ...], speed: 0.8, mode: loop, radius: 0.25, height: 1.75}]
    crowd:   {count: 12, seed: 1, center: [0, 0], inner_radius: 1.5, outer_radius: 4.5,
              min_speed: 0.5, max_speed: 1.5, waypoints: 4}   # optional, see below

Every entry may carry ``reflectivity`` (0..255, the OS1's calibrated reflectivity). Unknown
keys anywhere, missing required keys and bad values raise :class:`WorldError` naming the file
and the entry, so a typo never silently drops an obstacle.

People move along their polyline at constant speed; ``mode`` is ``loop`` (closed polygon),
``pingpong`` (there and back) or ``stand`` (stays at the first point). ``phase`` [s] shifts a
person along the path. Positions are a pure function of time, so every node that loads the
same file computes the same people at the same time.

``crowd`` adds ``count`` randomized people (named ``crowd0``, ``crowd1``, ...) drawn from
``seed``: each walks a loop or a there-and-back path of ``waypoints`` random points in the ring
between ``inner_radius`` and ``outer_radius`` around ``center`` at a speed drawn from
[``min_speed``, ``max_speed``] (at most 1.5 m/s) with a random phase. Every point *and every
segment* of a path keeps ``inner_radius`` from the centre, so the crowd walks around the robot's
trick area but never through it. The same seed gives the same crowd (see :func:`crowd_people`).
"""

import math
import os
import random

import yaml

DEFAULT_REFLECTIVITY = {"wall": 60, "box": 40, "table": 50, "cylinder": 30, "person": 25, "placed": 25}

_KEYS = {
    "wall": ({"from", "to"}, {"thickness", "height", "z", "reflectivity", "name"}),
    "box": ({"center", "size"}, {"name", "yaw", "z", "reflectivity"}),
    "table": ({"center", "size"}, {"name", "height", "yaw", "top_thickness", "leg_size", "reflectivity"}),
    "cylinder": ({"center", "radius", "height"}, {"name", "z", "reflectivity"}),
    "person": ({"name", "path"}, {"speed", "mode", "radius", "height", "phase", "reflectivity"}),
}
_TOP_KEYS = {"name", "description", "floor", "ceiling", "walls", "boxes", "tables", "cylinders", "people", "crowd"}
_CROWD_KEYS = {
    "count", "seed", "center", "inner_radius", "outer_radius", "min_speed", "max_speed", "waypoints",
    "min_radius", "max_radius", "height",
}
#: Fastest walker a crowd may have [m/s] (issue 10: people walk at up to 1.5 m/s).
CROWD_MAX_SPEED = 1.5
_SECTION_KIND = {"walls": "wall", "boxes": "box", "tables": "table", "cylinders": "cylinder", "people": "person"}
PERSON_MODES = ("loop", "pingpong", "stand")


class WorldError(ValueError):
    """A world file or a world request is invalid; the message says where and why."""


class Box:
    """A box standing on z0 with a yaw about the vertical axis.

    Attributes:
        name: Entry name.
        cx, cy: Centre in the world frame [m].
        hx, hy: Half sizes along the box's own x and y axes [m].
        z0, z1: Bottom and top height [m].
        yaw: Rotation about z [rad].
        reflectivity: OS1 reflectivity 0..255.
    """

    __slots__ = ("name", "cx", "cy", "hx", "hy", "z0", "z1", "yaw", "reflectivity")

    def __init__(
        self,
        name: str,
        cx: float,
        cy: float,
        hx: float,
        hy: float,
        z0: float,
        z1: float,
        yaw: float = 0.0,
        reflectivity: int = 40,
    ) -> None:
        self.name = name
        self.cx, self.cy, self.hx, self.hy = float(cx), float(cy), float(hx), float(hy)
        self.z0, self.z1, self.yaw = float(z0), float(z1), float(yaw)
        self.reflectivity = int(reflectivity)

    def bounding_radius(self) -> float:
        """Radius of the vertical cylinder around the box's footprint [m]."""
        return math.hypot(self.hx, self.hy)


class Cylinder:
    """A vertical cylinder (person, pillar, placed obstacle).

    Attributes:
        name: Entry name.
        cx, cy: Axis position in the world frame [m].
        radius: Radius [m].
        z0, z1: Bottom and top height [m].
        reflectivity: OS1 reflectivity 0..255.
        kind: "cylinder", "person" or "placed".
    """

    __slots__ = ("name", "cx", "cy", "radius", "z0", "z1", "reflectivity", "kind")

    def __init__(
        self,
        name: str,
        cx: float,
        cy: float,
        radius: float,
        z0: float,
        z1: float,
        reflectivity: int = 30,
        kind: str = "cylinder",
    ) -> None:
        self.name = name
        self.cx, self.cy, self.radius = float(cx), float(cy), float(radius)
        self.z0, self.z1 = float(z0), float(z1)
        self.reflectivity = int(reflectivity)
        self.kind = kind

    def bounding_radius(self) -> float:
        """Radius of the footprint [m]."""
        return self.radius


class Person:
    """A person walking a scripted polyline at constant speed.

    Args:
        name: Unique name.
        path: List of (x, y) way points [m].
        speed: Walking speed [m/s].
        mode: "loop", "pingpong" or "stand".
        radius: Body radius [m].
        height: Body height [m].
        phase: Time offset along the path [s].
        reflectivity: OS1 reflectivity 0..255.
    """

    def __init__(
        self,
        name: str,
        path: list,
        speed: float = 0.8,
        mode: str = "loop",
        radius: float = 0.25,
        height: float = 1.75,
        phase: float = 0.0,
        reflectivity: int = 25,
    ) -> None:
        self.name = name
        pts = [(float(p[0]), float(p[1])) for p in path]
        if mode == "loop" and len(pts) > 1:
            pts = pts + [pts[0]]
        elif mode == "pingpong" and len(pts) > 1:
            pts = pts + pts[-2::-1]
        self.points = pts
        self.speed, self.mode = float(speed), mode
        self.radius, self.height, self.phase = float(radius), float(height), float(phase)
        self.reflectivity = int(reflectivity)
        self.seg_len = [math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(pts[:-1], pts[1:])]
        self.length = sum(self.seg_len)

    def position(self, t: float) -> tuple:
        """Return the (x, y) position at time t [s] since the world epoch."""
        if self.mode == "stand" or self.length <= 0.0 or self.speed <= 0.0:
            return self.points[0]
        s = math.fmod((t + self.phase) * self.speed, self.length)
        if s < 0.0:
            s += self.length
        for (a, b), seg in zip(zip(self.points[:-1], self.points[1:]), self.seg_len):
            if s <= seg and seg > 0.0:
                f = s / seg
                return (a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]))
            s -= seg
        return self.points[-1]

    def cylinder(self, t: float) -> Cylinder:
        """Return the person's body as a cylinder at time t [s]."""
        x, y = self.position(t)
        return Cylinder(self.name, x, y, self.radius, 0.0, self.height, self.reflectivity, "person")


class World:
    """Static geometry, scripted people and run-time obstacles.

    Attributes:
        name: World name.
        floor_z: Floor height [m].
        ceiling_z: Ceiling height [m] or None.
        boxes: Static boxes (walls and tables are boxes too).
        cylinders: Static cylinders.
        people: Scripted people.
        placed: Run-time obstacles by name (see :meth:`place`).
        placed_boxes: Run-time boxes by name (see :meth:`place_box`).
    """

    def __init__(self, name: str = "empty", floor_z: float = 0.0, ceiling_z: float = None) -> None:
        self.name = name
        self.floor_z = float(floor_z)
        self.ceiling_z = None if ceiling_z is None else float(ceiling_z)
        self.boxes = []
        self.cylinders = []
        self.people = []
        self.placed = {}
        self.placed_boxes = {}

    # -- run-time obstacles -------------------------------------------------------------------
    def place(self, name: str, x: float, y: float, radius: float, height: float) -> str:
        """Add or move the cylinder called name.

        Returns:
            "added" or "moved".

        Raises:
            WorldError: empty name, non-finite values, radius or height not > 0.
        """
        if not name:
            raise WorldError("place_obstacle: name must not be empty")
        for label, v in (("x", x), ("y", y), ("radius", radius), ("height", height)):
            if not isinstance(v, (int, float)) or not math.isfinite(v):
                raise WorldError("place_obstacle %r: %s must be a finite number, got %r" % (name, label, v))
        if radius <= 0.0 or height <= 0.0:
            raise WorldError("place_obstacle %r: radius and height must be > 0 (got %g, %g)" % (name, radius, height))
        if radius > 5.0 or height > 10.0:
            raise WorldError(
                "place_obstacle %r: radius <= 5 m and height <= 10 m (got %g, %g)" % (name, radius, height)
            )
        result = "moved" if name in self.placed else "added"
        self.placed[name] = Cylinder(
            name, x, y, radius, self.floor_z, self.floor_z + height, DEFAULT_REFLECTIVITY["placed"], "placed"
        )
        return result

    def place_box(self, name: str, x: float, y: float, yaw: float, size_x: float, size_y: float, height: float) -> str:
        """Add or move the run-time box called name (a bag, a case, a wall panel).

        Returns:
            "added" or "moved".

        Raises:
            WorldError: empty name, non-finite values, sizes not in (0, 20] m, height not in (0, 10] m.
        """
        if not name:
            raise WorldError("place_box: name must not be empty")
        for label, v in (("x", x), ("y", y), ("yaw", yaw), ("size_x", size_x), ("size_y", size_y), ("height", height)):
            if not isinstance(v, (int, float)) or not math.isfinite(v):
                raise WorldError("place_box %r: %s must be a finite number, got %r" % (name, label, v))
        if not (0.0 < size_x <= 20.0 and 0.0 < size_y <= 20.0 and 0.0 < height <= 10.0):
            raise WorldError("place_box %r: sizes must be in (0, 20] m and height in (0, 10] m (got %g, %g, %g)" % (
                name, size_x, size_y, height))
        result = "moved" if name in self.placed_boxes else "added"
        boxes = dict(self.placed_boxes)  # swap, never mutate: the caster reads it from another thread
        boxes[name] = Box(name, x, y, 0.5 * size_x, 0.5 * size_y, self.floor_z, self.floor_z + height, yaw,
                          DEFAULT_REFLECTIVITY["placed"])
        self.placed_boxes = boxes
        return result

    def remove(self, name: str) -> None:
        """Remove the run-time obstacle (cylinder or box) called name.

        Raises:
            WorldError: no obstacle has that name.
        """
        if name in self.placed_boxes:
            boxes = dict(self.placed_boxes)
            del boxes[name]
            self.placed_boxes = boxes
            return
        if name not in self.placed:
            known = sorted(self.placed) + sorted(self.placed_boxes)
            raise WorldError("remove obstacle %r: no such obstacle (known: %s)" % (name, known or "none"))
        del self.placed[name]

    def all_boxes(self) -> list:
        """Static boxes (walls, tables, furniture) and run-time boxes."""
        boxes = self.placed_boxes
        return list(self.boxes) + [boxes[k] for k in sorted(boxes)]

    # -- snapshots ----------------------------------------------------------------------------
    def dynamic_cylinders(self, t: float) -> list:
        """People at time t [s] since the epoch, then placed obstacles."""
        placed = self.placed  # one read: another thread may swap the dict
        return [p.cylinder(t) for p in self.people] + [placed[k] for k in sorted(placed)]

    def all_cylinders(self, t: float) -> list:
        """Static cylinders, people at time t and placed obstacles."""
        return list(self.cylinders) + self.dynamic_cylinders(t)


# -- loading ----------------------------------------------------------------------------------
def resolve_world_path(name: str, worlds_dir: str) -> str:
    """Map a world name ("lab") or a path to an existing YAML file.

    Raises:
        WorldError: the file does not exist.
    """
    if not name:
        raise WorldError("world name is empty")
    if name.endswith((".yaml", ".yml")) or os.sep in name:
        path = name
    else:
        path = os.path.join(worlds_dir, name + ".yaml")
    if not os.path.isfile(path):
        known = (
            sorted(f[:-5] for f in os.listdir(worlds_dir) if f.endswith(".yaml")) if os.path.isdir(worlds_dir) else []
        )
        raise WorldError("world %r: file %s not found (known worlds: %s)" % (name, path, ", ".join(known) or "none"))
    return path


def load_world(path: str) -> World:
    """Load and validate a world YAML file.

    Raises:
        WorldError: unreadable file, unknown or missing keys, bad values.
    """
    try:
        with open(path) as f:
            data = yaml.safe_load(f)
    except (OSError, yaml.YAMLError) as e:
        raise WorldError("%s: cannot read world file: %s" % (path, e)) from e
    return world_from_dict(data, path)


def world_from_dict(data: dict, where: str = "world") -> World:
    """Build a world from parsed YAML (see the module docstring for the schema).

    Raises:
        WorldError: unknown or missing keys, bad values.
    """
    if not isinstance(data, dict):
        raise WorldError("%s: top level must be a mapping, got %s" % (where, type(data).__name__))
    unknown = set(data) - _TOP_KEYS
    if unknown:
        raise WorldError(
            "%s: unknown top-level key(s) %s (allowed: %s)" % (where, sorted(unknown), ", ".join(sorted(_TOP_KEYS)))
        )
    floor = _section_dict(data, "floor", where, {"z"})
    ceiling = _section_dict(data, "ceiling", where, {"z"})
    world = World(
        str(data.get("name", os.path.splitext(os.path.basename(where))[0])),
        _num(floor.get("z", 0.0), where + ": floor.z"),
        None if not ceiling else _num(ceiling.get("z"), where + ": ceiling.z", lo=0.5),
    )
    names = set()
    for section, kind in sorted(_SECTION_KIND.items()):
        entries = data.get(section) or []
        if not isinstance(entries, list):
            raise WorldError("%s: %s must be a list" % (where, section))
        for i, e in enumerate(entries):
            ctx = "%s: %s[%d]" % (where, section, i)
            if not isinstance(e, dict):
                raise WorldError("%s: must be a mapping, got %r" % (ctx, e))
            required, optional = _KEYS[kind]
            bad = set(e) - required - optional
            if bad:
                raise WorldError(
                    "%s: unknown key(s) %s for a %s (allowed: %s)"
                    % (ctx, sorted(bad), kind, ", ".join(sorted(required | optional)))
                )
            missing = required - set(e)
            if missing:
                raise WorldError("%s: missing required key(s) %s" % (ctx, sorted(missing)))
            name = str(e.get("name", "%s%d" % (kind, i)))
            if "name" in e:
                if name in names:
                    raise WorldError("%s: duplicate name %r" % (ctx, name))
                names.add(name)
            refl = _num(e.get("reflectivity", DEFAULT_REFLECTIVITY[kind]), ctx + ".reflectivity", lo=0, hi=255)
            _ADD[kind](world, e, ctx, world.floor_z + 0.0, name, refl)
    if data.get("crowd") is not None:
        _add_crowd(world, data["crowd"], where + ": crowd", names)
    return world


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


def _add_crowd(world: World, e: object, ctx: str, names: set) -> None:
    if not isinstance(e, dict):
        raise WorldError("%s: must be a mapping like {count: 12, seed: 1}" % ctx)
    bad = set(e) - _CROWD_KEYS
    if bad:
        raise WorldError("%s: unknown key(s) %s (allowed: %s)" % (ctx, sorted(bad), ", ".join(sorted(_CROWD_KEYS))))
    if "count" not in e:
        raise WorldError("%s: missing required key(s) ['count']" % ctx)
    count, seed, waypoints = e["count"], e.get("seed", 0), e.get("waypoints", 4)
    for label, v in (("count", count), ("seed", seed), ("waypoints", waypoints)):
        if isinstance(v, bool) or not isinstance(v, int):
            raise WorldError("%s.%s: expected an integer, got %r" % (ctx, label, v))
    people = crowd_people(
        count,
        seed,
        _xy(e.get("center", [0.0, 0.0]), ctx + ".center"),
        _num(e.get("inner_radius", 1.5), ctx + ".inner_radius"),
        _num(e.get("outer_radius", 4.5), ctx + ".outer_radius"),
        _num(e.get("min_speed", 0.5), ctx + ".min_speed"),
        _num(e.get("max_speed", CROWD_MAX_SPEED), ctx + ".max_speed"),
        waypoints,
        _num(e.get("min_radius", 0.18), ctx + ".min_radius"),
        _num(e.get("max_radius", 0.27), ctx + ".max_radius"),
        _num(e.get("height", 1.75), ctx + ".height", lo=0.5, hi=2.5),
    )
    clash = names & {p.name for p in people}
    if clash:
        raise WorldError("%s: name(s) %s already used by other entries" % (ctx, sorted(clash)))
    world.people.extend(people)


def _add_wall(world: World, e: dict, ctx: str, floor: float, name: str, refl: float) -> None:
    ax, ay = _xy(e["from"], ctx + ".from")
    bx, by = _xy(e["to"], ctx + ".to")
    length = math.hypot(bx - ax, by - ay)
    if length <= 0.0:
        raise WorldError("%s: wall has zero length" % ctx)
    thick = _num(e.get("thickness", 0.1), ctx + ".thickness", lo=0.01)
    height = _num(e.get("height", 2.5), ctx + ".height", lo=0.01)
    z = floor + _num(e.get("z", 0.0), ctx + ".z")
    world.boxes.append(
        Box(
            name, (ax + bx) / 2, (ay + by) / 2, length / 2, thick / 2, z, z + height, math.atan2(by - ay, bx - ax), refl
        )
    )


def _add_box(world: World, e: dict, ctx: str, floor: float, name: str, refl: float) -> None:
    cx, cy = _xy(e["center"], ctx + ".center")
    size = e["size"]
    if not isinstance(size, list) or len(size) != 3:
        raise WorldError("%s.size: expected [lx, ly, lz], got %r" % (ctx, size))
    lx, ly, lz = (_num(v, ctx + ".size", lo=0.01) for v in size)
    z = floor + _num(e.get("z", 0.0), ctx + ".z")
    yaw = _num(e.get("yaw", 0.0), ctx + ".yaw")
    world.boxes.append(Box(name, cx, cy, lx / 2, ly / 2, z, z + lz, yaw, refl))


def _add_table(world: World, e: dict, ctx: str, floor: float, name: str, refl: float) -> None:
    """A table is a top slab plus four legs, so the LiDAR sees under it as a real one does."""
    cx, cy = _xy(e["center"], ctx + ".center")
    lx, ly = _xy(e["size"], ctx + ".size")
    if lx <= 0.1 or ly <= 0.1:
        raise WorldError("%s.size: table must be larger than 0.1 m each way" % ctx)
    height = _num(e.get("height", 0.75), ctx + ".height", lo=0.1)
    top = _num(e.get("top_thickness", 0.04), ctx + ".top_thickness", lo=0.005, hi=height)
    leg = _num(e.get("leg_size", 0.05), ctx + ".leg_size", lo=0.005, hi=min(lx, ly) / 2)
    yaw = _num(e.get("yaw", 0.0), ctx + ".yaw")
    world.boxes.append(Box(name + "/top", cx, cy, lx / 2, ly / 2, floor + height - top, floor + height, yaw, refl))
    c, s = math.cos(yaw), math.sin(yaw)
    for i, (sx, sy) in enumerate(((1, 1), (1, -1), (-1, -1), (-1, 1))):
        ux, uy = sx * (lx / 2 - leg / 2), sy * (ly / 2 - leg / 2)
        world.boxes.append(
            Box(
                "%s/leg%d" % (name, i),
                cx + c * ux - s * uy,
                cy + s * ux + c * uy,
                leg / 2,
                leg / 2,
                floor,
                floor + height - top,
                yaw,
                refl,
            )
        )


def _add_cylinder(world: World, e: dict, ctx: str, floor: float, name: str, refl: float) -> None:
    cx, cy = _xy(e["center"], ctx + ".center")
    radius = _num(e["radius"], ctx + ".radius", lo=0.01)
    height = _num(e["height"], ctx + ".height", lo=0.01)
    z = floor + _num(e.get("z", 0.0), ctx + ".z")
    world.cylinders.append(Cylinder(name, cx, cy, radius, z, z + height, refl, "cylinder"))


def _add_person(world: World, e: dict, ctx: str, floor: float, name: str, refl: float) -> None:
    path = e["path"]
    if not isinstance(path, list) or not path:
        raise WorldError("%s.path: expected a non-empty list of [x, y]" % ctx)
    pts = [_xy(p, "%s.path[%d]" % (ctx, j)) for j, p in enumerate(path)]
    mode = e.get("mode", "loop")
    if mode not in PERSON_MODES:
        raise WorldError("%s.mode: %r is not one of %s" % (ctx, mode, ", ".join(PERSON_MODES)))
    world.people.append(
        Person(
            name,
            pts,
            _num(e.get("speed", 0.8), ctx + ".speed", lo=0.0, hi=5.0),
            mode,
            _num(e.get("radius", 0.25), ctx + ".radius", lo=0.05, hi=2.0),
            _num(e.get("height", 1.75), ctx + ".height", lo=0.1, hi=3.0),
            _num(e.get("phase", 0.0), ctx + ".phase"),
            refl,
        )
    )


_ADD = {"wall": _add_wall, "box": _add_box, "table": _add_table, "cylinder": _add_cylinder, "person": _add_person}


def _section_dict(data: dict, key: str, where: str, allowed: set) -> dict:
    value = data.get(key)
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise WorldError("%s: %s must be a mapping like {z: 0.0}" % (where, key))
    bad = set(value) - allowed
    if bad:
        raise WorldError("%s: %s: unknown key(s) %s (allowed: %s)" % (where, key, sorted(bad), sorted(allowed)))
    return value


def _num(v: object, ctx: str, lo: float = None, hi: float = None) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise WorldError("%s: expected a finite number, got %r" % (ctx, v))
    if lo is not None and v < lo or hi is not None and v > hi:
        raise WorldError("%s: %r out of range [%s, %s]" % (ctx, v, lo, hi))
    return float(v)


def _xy(v: object, ctx: str) -> tuple:
    if not isinstance(v, (list, tuple)) or len(v) != 2:
        raise WorldError("%s: expected [x, y], got %r" % (ctx, v))
    return _num(v[0], ctx), _num(v[1], ctx)
