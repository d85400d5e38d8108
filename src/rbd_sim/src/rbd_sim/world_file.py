"""The world file: its YAML schema, read into a :class:`rbd_sim.world.World` (ROS-free).

A world file is YAML (see ``worlds/lab.yaml``)::

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

``crowd`` adds a random crowd, see :mod:`rbd_sim.crowd`.
"""

import math
import os

import yaml

from rbd_sim.crowd import CROWD_MAX_SPEED, crowd_people
from rbd_sim.shapes import DEFAULT_REFLECTIVITY, PERSON_MODES, Box, Cylinder, Person, WorldError
from rbd_sim.world import World

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
_SECTION_KIND = {"walls": "wall", "boxes": "box", "tables": "table", "cylinders": "cylinder", "people": "person"}


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
