"""Ray caster against a brute-force float64 reference, and simple exact geometry."""

import math
import os

import numpy as np
import pytest

from rbd_geometry.rotation import rpy_to_matrix
from rbd_sim import os1
from rbd_sim.raycast import CEILING_ID, FIRST_PRIMITIVE_ID, FLOOR_ID, NO_HIT, Raycaster
from rbd_sim.shapes import Box, Cylinder
from rbd_sim.world import World
from rbd_sim.world_file import load_world

WORLDS_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "worlds")

META = os1.load_metadata(os1.DEFAULT_METADATA)


def reference_cast(dirs, origins, rot, trans, floor_z, ceiling_z, boxes, cylinders):
    """Slab/quadratic test of every ray against every primitive, float64, no culling."""
    d = dirs.dot(rot.T)  # (H, W, 3)
    o = (origins.dot(rot.T) + trans)[None, :, :] + np.zeros_like(d)
    best = np.full(d.shape[:2], np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        for z in (floor_z, ceiling_z):
            if z is None:
                continue
            tp = (z - o[..., 2]) / d[..., 2]
            best = np.where((tp > 0) & (tp < best), tp, best)
        for b in boxes:
            c, s = math.cos(b.yaw), math.sin(b.yaw)
            px, py = o[..., 0] - b.cx, o[..., 1] - b.cy
            qx, qy = c * px + s * py, -s * px + c * py
            ex, ey = c * d[..., 0] + s * d[..., 1], -s * d[..., 0] + c * d[..., 1]
            tn, tf = np.full(best.shape, -np.inf), np.full(best.shape, np.inf)
            for p, e, lo, hi in ((qx, ex, -b.hx, b.hx), (qy, ey, -b.hy, b.hy), (o[..., 2], d[..., 2], b.z0, b.z1)):
                t1, t2 = (lo - p) / e, (hi - p) / e
                tn = np.fmax(tn, np.fmin(t1, t2))
                tf = np.fmin(tf, np.fmax(t1, t2))
            ok = (tn <= tf) & (tn > 0)
            best = np.where(ok & (tn < best), tn, best)
        for cy in cylinders:
            px, py = o[..., 0] - cy.cx, o[..., 1] - cy.cy
            a = d[..., 0] ** 2 + d[..., 1] ** 2
            bb = d[..., 0] * px + d[..., 1] * py
            cc = px**2 + py**2 - cy.radius**2
            disc = bb * bb - a * cc
            tn = (-bb - np.sqrt(np.maximum(disc, 0))) / a
            z = o[..., 2] + tn * d[..., 2]
            ok = (disc >= 0) & (tn > 0) & (z >= cy.z0) & (z <= cy.z1)
            best = np.where(ok & (tn < best), tn, best)
            for cap in (cy.z0, cy.z1):
                tc = (cap - o[..., 2]) / d[..., 2]
                qx, qy = px + tc * d[..., 0], py + tc * d[..., 1]
                ok = (tc > 0) & (qx**2 + qy**2 <= cy.radius**2)
                best = np.where(ok & (tc < best), tc, best)
    return best


@pytest.mark.parametrize("columns", [512, 2048])
@pytest.mark.parametrize("world_name", ["lab", "fair"])
def test_matches_brute_force_reference(columns, world_name):
    world = load_world("%s/%s.yaml" % (WORLDS_DIR, world_name))
    model = os1.Os1Model(META, columns, 10, seed=3)
    rng = np.random.default_rng(42)
    for k in range(4):
        rot = rpy_to_matrix(rng.uniform(-0.25, 0.25), rng.uniform(-0.25, 0.25), rng.uniform(-math.pi, math.pi))
        trans = np.array([rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.2, 0.5)])
        cyl = world.all_cylinders(k * 3.7)
        res = model.raycaster.cast(rot, trans, world.floor_z, world.ceiling_z, world.boxes, cyl, 120.0)
        ref = reference_cast(
            model.directions, model.origins, rot, trans, world.floor_z, world.ceiling_z, world.boxes, cyl
        )
        both = np.isfinite(ref) & np.isfinite(res.dist)
        mismatch = np.isfinite(ref) != np.isfinite(res.dist)
        assert mismatch.mean() < 1e-3
        err = np.abs(res.dist[both] - ref[both])
        # Rays grazing an edge may hit a different face; nearly all agree to float32 precision.
        assert np.mean(err < 2e-3) > 0.998, np.sort(err)[-10:]


def test_box_in_front_distance_and_ids():
    world = World("t")
    world.boxes.append(Box("wall", 3.0, 0.0, 0.05, 2.0, 0.0, 2.0))
    world.cylinders.append(Cylinder("c", -2.0, 0.0, 0.3, 0.0, 1.0))
    model = os1.Os1Model(META, 1024, 10, range_noise_std=0.0, seed=0)
    res = model.raycaster.cast(np.eye(3), np.array([0.0, 0.0, 0.4]), 0.0, 2.5, world.boxes, world.cylinders)
    # Column W/2 looks along +x in os_sensor; horizontal-ish rows hit the face at x = 2.95.
    w = model.columns
    row = int(np.argmin(np.abs(model.altitudes)))
    col = int(np.argmin(np.abs(np.arctan2(model.directions[row, :, 1], model.directions[row, :, 0]))))
    assert abs(col - w // 2) <= 16
    d = model.directions[row, col]
    o = model.origins[col]
    expect = (2.95 - o[0]) / d[0]
    assert res.dist[row, col] == pytest.approx(expect, abs=1e-4)
    assert res.hit[row, col] == FIRST_PRIMITIVE_ID + 0
    # The top beams see the ceiling behind the cylinder, bottom beams the floor.
    assert np.all(res.hit[-1, :] == FLOOR_ID)
    assert np.any(res.hit[0, :] == CEILING_ID)
    assert np.any(res.hit == FIRST_PRIMITIVE_ID + 1)


def test_no_geometry_means_no_hit():
    model = os1.Os1Model(META, 512, 10, seed=0)
    res = model.raycaster.cast(np.eye(3), np.zeros(3), None, None)
    assert np.all(res.hit == NO_HIT) and np.all(np.isinf(res.dist))


def test_max_range_drops_far_hits():
    world = World("t")
    world.boxes.append(Box("far", 50.0, 0.0, 0.5, 5.0, 0.0, 3.0))
    model = os1.Os1Model(META, 512, 10, seed=0)
    near = model.raycaster.cast(np.eye(3), np.array([0, 0, 1.0]), None, None, world.boxes, [], max_range=120.0)
    cut = model.raycaster.cast(np.eye(3), np.array([0, 0, 1.0]), None, None, world.boxes, [], max_range=40.0)
    assert np.isfinite(near.dist).sum() > 0
    assert np.isfinite(cut.dist).sum() == 0


def test_origin_inside_cylinder_sees_inner_wall():
    model = os1.Os1Model(META, 512, 10, seed=0)
    cyl = [Cylinder("p", 0.0, 0.0, 0.5, 0.0, 2.0)]
    res = model.raycaster.cast(np.eye(3), np.array([0, 0, 0.4]), None, None, [], cyl)
    mid = int(np.argmin(np.abs(model.altitudes)))
    assert np.all(np.abs(res.dist[mid] - 0.5) < 0.03)


def test_bad_shapes_rejected():
    with pytest.raises(ValueError):
        Raycaster(np.zeros((4, 8, 3)), np.zeros((4, 3)))


def test_motion_matches_reference():
    world = load_world("%s/fair.yaml" % WORLDS_DIR)
    model = os1.Os1Model(META, 1024, 10, seed=3)
    rot = rpy_to_matrix(0.05, -0.1, 2.0)
    trans = np.array([0.3, -0.2, 0.35])
    vel, yaw_rate = np.array([0.6, -0.3, 0.0]), 0.8
    col_t = np.arange(1024) / (10.0 * 1024)
    cyl = world.all_cylinders(5.0)
    res = model.raycaster.cast(rot, trans, 0.0, None, world.boxes, cyl, 120.0, (vel, yaw_rate, col_t))
    # Apply the motion by hand: column c turned by yaw_rate * t_c about z through trans, shifted by vel * t_c.
    psi = yaw_rate * col_t
    rz = np.zeros((1024, 3, 3))
    rz[:, 0, 0], rz[:, 0, 1] = np.cos(psi), -np.sin(psi)
    rz[:, 1, 0], rz[:, 1, 1], rz[:, 2, 2] = np.sin(psi), np.cos(psi), 1
    d = np.einsum("cij,hcj->hci", rz, model.directions.dot(rot.T))
    o = trans + np.einsum("cij,cj->ci", rz, model.origins.dot(rot.T)) + vel[None, :] * col_t[:, None]
    ref = reference_cast(d, o, np.eye(3), np.zeros(3), 0.0, None, world.boxes, cyl)
    both = np.isfinite(ref) & np.isfinite(res.dist)
    assert (np.isfinite(ref) != np.isfinite(res.dist)).mean() < 1e-3
    assert np.mean(np.abs(res.dist[both] - ref[both]) < 2e-3) > 0.998
