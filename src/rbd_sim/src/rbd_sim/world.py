"""Simulated world: static geometry, people on scripted paths, obstacles placed at run time.

ROS-free. The shapes are in :mod:`rbd_sim.shapes`, the YAML world file in :mod:`rbd_sim.world_file`,
the random crowd in :mod:`rbd_sim.crowd`.
"""

import math

from rbd_sim.shapes import DEFAULT_REFLECTIVITY, Box, Cylinder, WorldError


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
