"""The lattice's configuration space (rbd_controller.cspace): its two ways of building a heading bin agree."""

import numpy as np

from rbd_controller.cspace import CSpace
from rbd_controller.lattice import LatticePlanner

ZONE = (0.70, 0.35, 0.55, 0.35)


def test_walls_build_the_same_configuration_space_as_stamping_or_more():
    # Many obstacle cells switch the grid's build from stamping the rectangle on each cell to dilating
    # by its two sides; the second must flag every cell the first does (the exact check clears the rest).
    walls = np.concatenate([np.stack([np.full(200, -1.5), np.linspace(-1.5, 1.5, 200)], 1),
                            np.stack([np.linspace(-1.5, 1.5, 200), np.full(200, 1.2)], 1)])
    planner = LatticePlanner(ZONE)
    window = planner._window((-1.0, 0.0, 0.0), (1.0, 0.0, 0.0))
    space = CSpace(window, planner._obstacles(window, None, walls), planner.zone_for(0.3), planner.bin,
                   planner.headings, None, planner.resolution)
    h, w = space.blocked.shape[1:]
    for k in range(0, planner.headings, 7):
        sides = np.zeros((h, w), dtype=bool)
        space._build_by_sides(k, sides)
        cells = (space._occ[:, None, :] - space._kernel(k)[None, :, :]).reshape(-1, 2)
        ok = (cells[:, 0] >= 0) & (cells[:, 0] < h) & (cells[:, 1] >= 0) & (cells[:, 1] < w)
        stamped = np.zeros((h, w), dtype=bool)
        stamped[cells[ok, 0], cells[ok, 1]] = True
        assert stamped.any() and not (stamped & ~sides).any(), k
