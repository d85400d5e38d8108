"""The lattice's configuration space (rbd_controller.cspace): a bin's grid is the rectangle stamped on each cell."""

import numpy as np

from rbd_controller.cspace import CSpace, obstacle_grid
from rbd_controller.lattice import LatticePlanner

ZONE = (0.70, 0.35, 0.55, 0.35)


def stamped(space, k):
    """Reference: the bin's rotated rectangle stamped on every obstacle cell, one by one."""
    h, w = space.blocked.shape[1:]
    cells = (space._occ[:, None, :] - space._kernel(k)[None, :, :]).reshape(-1, 2)
    ok = (cells[:, 0] >= 0) & (cells[:, 0] < h) & (cells[:, 1] >= 0) & (cells[:, 1] < w)
    out = np.zeros((h, w), dtype=bool)
    out[cells[ok, 0], cells[ok, 1]] = True
    return out


def test_the_convolved_configuration_space_is_the_stamped_one():
    # Walls (many cells) and a box near the window's edge: the FFT dilation flags exactly the cells the
    # stamped rectangle does (edge cells included), for several bins.
    rng = np.random.default_rng(4)
    walls = np.concatenate([np.stack([np.full(60, -1.5), np.linspace(-1.5, 1.5, 60)], 1),
                            np.stack([np.linspace(-1.5, 1.5, 60), np.full(60, 1.2)], 1),
                            rng.uniform([2.6, -2.0], [3.0, -1.6], size=(20, 2))])
    planner = LatticePlanner(ZONE)
    window = planner._window((-1.0, 0.0, 0.0), (1.0, 0.0, 0.0))
    space = CSpace(window, obstacle_grid(window, planner.resolution, None, walls), planner.zone_for(0.3), planner.bin,
                   planner.headings, None, planner.resolution)
    for k in range(0, planner.headings, 7):
        got = space._dilated(k)
        want = stamped(space, k)
        assert want.any() and (got == want).all(), (k, int((got != want).sum()))
