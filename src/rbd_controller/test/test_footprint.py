"""footprint.grown_zone's age term against rbd_lidar's rule (zone_growth.cpp, gtests
VelocityAwareGrowthAddsTheCloudAge / CloudsUpToMaxCloudAgeAreJudged): the same numbers."""

import math

import numpy as np
import pytest

from rbd_controller.footprint import ZoneGrowth, grown_zone

ZONE = (0.70, 0.35, 0.55, 0.35)  # FRONT, LEFT, BACK, RIGHT: rbd_lidar's rest zone


def test_age_is_bounded_by_max_cloud_age_as_in_rbd_lidar():
    g = ZoneGrowth()
    assert g.max_age == 0.5  # rbd_lidar's max_cloud_age default
    # 0.4 m/s ahead: +0.28 m reaction, + 0.4 x age, the age counted up to 0.5 s and no further
    assert grown_zone(ZONE, 0.4, 0.0, 0.0, g, age=0.3)[0] == pytest.approx(0.70 + 0.28 + 0.12)
    assert grown_zone(ZONE, 0.4, 0.0, 0.0, g, age=0.5)[0] == pytest.approx(0.70 + 0.28 + 0.20)
    assert grown_zone(ZONE, 0.4, 0.0, 0.0, g, age=0.9)[0] == pytest.approx(0.70 + 0.28 + 0.20)
    assert grown_zone(ZONE, 0.4, 0.0, 0.0, g, age=math.inf)[0] == pytest.approx(0.70 + 0.28 + 0.20)
    # unknown age: the worst judged; a stamp ahead of the clock: 0
    assert grown_zone(ZONE, 0.4, 0.0, 0.0, g, age=math.nan)[0] == pytest.approx(0.70 + 0.28 + 0.20)
    assert grown_zone(ZONE, 0.4, 0.0, 0.0, g, age=-0.2)[0] == pytest.approx(0.70 + 0.28)
    # the driver's limits (0.5 m/s, 1 rad/s): 0.50 m capped + 0.8 m/s x 0.5 s = 1.60 m (the README's number)
    assert grown_zone(ZONE, 0.5, 0.0, 1.0, g, age=0.5)[0] == pytest.approx(1.60)
    # the thesis' 0.3 m/s turning at 0.63 rad/s: 1.04 m fresh, 1.29 m at 0.5 s
    assert grown_zone(ZONE, 0.3, 0.0, 0.63, g, age=0.0)[0] == pytest.approx(0.70 + 0.489 * 0.7)
    assert grown_zone(ZONE, 0.3, 0.0, 0.63, g, age=0.5)[0] == pytest.approx(0.70 + 0.489 * 1.2)
    # a smaller bound is honoured
    short = ZoneGrowth(max_age=0.3)
    assert grown_zone(ZONE, 0.4, 0.0, 0.0, short, age=0.5)[0] == pytest.approx(0.70 + 0.28 + 0.12)
    # standing still, an old cloud grows nothing
    assert np.allclose(grown_zone(ZONE, 0.0, 0.0, 0.0, g, age=0.5), ZONE)


def test_max_age_is_validated():
    for bad in (-0.1, math.nan, math.inf, True):
        with pytest.raises(ValueError):
            ZoneGrowth(max_age=bad)


def test_growth_from_params_reads_rbd_lidars_names_and_refuses_bad_values():
    from rbd_controller.footprint import growth_from_params

    params = {"/l/reaction_time": 0.5, "/l/rotation_lever": 0.2, "/l/max_growth": 0.4, "/l/velocity_aware": False,
              "/l/max_cloud_age": 0.3}
    g = growth_from_params(lambda name, default: params.get(name, default), "/l")
    assert (g.reaction_time, g.rotation_lever, g.max_growth, g.enabled, g.max_age) == (0.5, 0.2, 0.4, False, 0.3)
    params["/l/reaction_time"] = -1.0
    with pytest.raises(ValueError):
        growth_from_params(lambda name, default: params.get(name, default), "/l")
