"""Tests of the reference centerline route (reference/centerline.py) on analytic vessels: a
slanted capped cylinder, a capped half torus, an open tube and a Y of three cylinders, whose
true axes, radii and junction are known. They check the oracle itself: `vesselmsr centerline`
is compared against it, never the other way round."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import centerline as cl  # noqa: E402

trimesh = pytest.importorskip("trimesh")

R = 2.0
H = R / 6  # voxel: 6 per radius keeps each test well under a second


def _faces(m) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(m.vertices, np.float64), np.asarray(m.faces, np.int64)


def _tube(centres: np.ndarray, frames: np.ndarray, radius: float, sections: int, caps: bool):
    """A tube of circular cross-sections: ring i has centre centres[i] and in-plane axes
    frames[i] = (u, v); flat caps (a fan around the end centres) when `caps`."""
    n = len(centres)
    ang = 2 * math.pi * np.arange(sections) / sections
    rings = (
        centres[:, None, :]
        + radius * np.cos(ang)[None, :, None] * frames[:, 0][:, None, :]
        + radius * np.sin(ang)[None, :, None] * frames[:, 1][:, None, :]
    )
    V = rings.reshape(-1, 3)
    F = []
    for i in range(n - 1):
        for j in range(sections):
            a, b = i * sections + j, i * sections + (j + 1) % sections
            c, d = a + sections, b + sections
            F += [[a, b, d], [a, d, c]]
    if caps:
        V = np.vstack([V, centres[0], centres[-1]])
        c0, c1 = len(V) - 2, len(V) - 1
        last = (n - 1) * sections
        for j in range(sections):
            F.append([c0, (j + 1) % sections, j])
            F.append([c1, last + j, last + (j + 1) % sections])
    return V, np.asarray(F, np.int64)


def _orient_outward(V, F):
    m = trimesh.Trimesh(V, F, process=False)
    if m.volume < 0:
        F = F[:, ::-1].copy()
    return V, F


def _rotation():
    return trimesh.transformations.rotation_matrix(0.5, [1.0, 2.0, 0.3])[:3, :3]


def _branch_arrays(doc):
    pts = np.concatenate([np.asarray(b["points"]) for b in doc["branches"]])
    rad = np.concatenate([np.asarray(b["radius"]) for b in doc["branches"]])
    return pts, rad


def test_capped_cylinder_axis_and_radius():
    L = 16.0
    rot = np.eye(4)
    rot[:3, :3] = _rotation()
    V, F = _faces(trimesh.creation.cylinder(radius=R, height=L, sections=128, transform=rot))
    doc = cl.centerline(V, F, H)
    assert len(doc["branches"]) == 1 and len(doc["junctions"]) == 0
    assert len(doc["endpoints"]) == 2
    assert not any(e["open_end"] for e in doc["endpoints"])
    axis = _rotation() @ [0.0, 0.0, 1.0]
    P, r = _branch_arrays(doc)
    s = P @ axis
    away = np.abs(s) <= L / 2 - R  # more than one radius from either cap
    assert away.sum() > 0.6 * (L - 2 * R) / H
    dist = np.linalg.norm(P - np.outer(s, axis), axis=1)
    print(f"cylinder: axis distance max {dist[away].max() / H:.3f} h, "
          f"radius error max {np.abs(r[away] - R).max() / H:.3f} h")
    assert dist[away].max() <= 0.5 * H
    assert np.abs(r[away] - R).max() <= 0.5 * H
    # the section's equivalent diameter of the 128-gon: 2R·sqrt(sin(2π/128)·128/(2π))
    eqd = np.asarray(doc["branches"][0]["equivalent_diameter"], float)[away]
    expect = 2 * R * math.sqrt(128 * math.sin(2 * math.pi / 128) / (2 * math.pi))
    assert np.abs(eqd - expect).max() <= 0.01 * R
    # the blunt ends are finished on the axis, at the caps
    ends = sorted(np.asarray(e["position"]) @ axis for e in doc["endpoints"])
    assert abs(ends[0] + L / 2) <= 0.5 * H and abs(ends[1] - L / 2) <= 0.5 * H
    assert abs(doc["branches"][0]["length"] - L) <= H


def test_half_torus_axis_and_radius():
    big = 8.0
    t = np.linspace(0.0, math.pi, 161)
    centres = np.stack([big * np.cos(t), big * np.sin(t), np.zeros_like(t)], axis=1)
    u = np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], axis=1)  # radial
    w = np.tile([0.0, 0.0, 1.0], (len(t), 1))
    V, F = _orient_outward(*_tube(centres, np.stack([u, w], axis=1), R, 96, caps=True))
    rot = _rotation()
    V = V @ rot.T
    doc = cl.centerline(V, F, H)
    assert len(doc["branches"]) == 1 and len(doc["junctions"]) == 0
    P, r = _branch_arrays(doc)
    Q = P @ rot  # back to the torus frame
    rho = np.hypot(Q[:, 0], Q[:, 1])
    dist = np.hypot(rho - big, Q[:, 2])
    ang = np.arctan2(Q[:, 1], Q[:, 0])
    # more than one radius (of arc along the axis) from either cap
    away = (ang * big >= R) & ((math.pi - ang) * big >= R) & (Q[:, 1] > -1e-9)
    assert away.sum() > 0.6 * (math.pi * big - 2 * R) / H
    print(f"half torus: axis distance max {dist[away].max() / H:.3f} h, "
          f"radius error max {np.abs(r[away] - R).max() / H:.3f} h")
    assert dist[away].max() <= 0.5 * H
    assert np.abs(r[away] - R).max() <= 0.5 * H


def test_open_tube_ends_at_the_openings():
    L = 16.0
    s = np.linspace(-L / 2, L / 2, 65)
    centres = np.stack([np.zeros_like(s), np.zeros_like(s), s], axis=1)
    frames = np.tile(np.array([[[1.0, 0, 0], [0, 1.0, 0]]]), (len(s), 1, 1))
    V, F = _tube(centres, frames, R, 96, caps=False)
    rot = _rotation()
    V = V @ rot.T
    doc = cl.centerline(V, F, H)
    assert len(doc["branches"]) == 1 and len(doc["junctions"]) == 0
    assert len(doc["endpoints"]) == 2 and all(e["open_end"] for e in doc["endpoints"])
    ends = sorted((np.asarray(e["position"]) @ rot)[2] for e in doc["endpoints"])
    assert abs(ends[0] + L / 2) <= 0.5 * H and abs(ends[1] - L / 2) <= 0.5 * H
    b = doc["branches"][0]
    assert b["start"] == "open_end" and b["end"] == "open_end"
    assert abs(b["length"] - L) <= 1.0 * H
    P, r = _branch_arrays(doc)
    z = P @ rot[:, 2]
    away = np.abs(z) <= L / 2 - R
    dist = np.linalg.norm(P - np.outer(z, rot[:, 2]), axis=1)
    assert dist[away].max() <= 0.5 * H
    assert np.abs(r[away] - R).max() <= 0.5 * H


def test_y_union_one_junction_three_branches():
    arm = 12.0
    rot = _rotation()
    centre = np.array([1.0, -2.0, 0.5])
    pieces = [trimesh.creation.icosphere(subdivisions=3, radius=R).apply_translation(centre)]
    tips = []
    for k in range(3):
        a = 2 * math.pi * k / 3
        d = rot @ [math.cos(a), math.sin(a), 0.0]
        tips.append(centre + arm * d)
        pieces.append(trimesh.creation.cylinder(radius=R, segment=[centre, centre + arm * d], sections=64))
    y = trimesh.boolean.union(pieces, engine="manifold")
    V, F = _faces(y)
    doc = cl.centerline(V, F, R / 4)  # coarser: the Y's box is large
    assert len(doc["junctions"]) == 1
    assert len(doc["branches"]) == 3
    assert len(doc["endpoints"]) == 3
    j = np.asarray(doc["junctions"][0]["position"])
    print(f"Y: junction {np.linalg.norm(j - centre) / R:.3f} R from the true one")
    assert np.linalg.norm(j - centre) <= R
    assert sorted(doc["junctions"][0]["branches"]) == [0, 1, 2]
    # every arm's branch ends near its tip (within the flat cap's reach: one radius)
    for tip in tips:
        d = min(np.linalg.norm(np.asarray(e["position"]) - tip) for e in doc["endpoints"])
        assert d <= 1.5 * R


def test_compare_figures():
    doc = {
        "voxel": 0.5,
        "branches": [{"length": 10.0, "points": [[0, 0, 0], [10, 0, 0]], "radius": [1.0, 1.0]}],
        "junctions": [],
        "endpoints": [{"position": [0, 0, 0], "open_end": True}, {"position": [10, 0, 0]}],
        "components": 1,
    }
    same = cl.compare(doc, doc)
    assert same["hausdorff_h"] == 0 and same["mean_h"] == 0
    assert same["mean_abs_radius_diff_h"] == 0
    assert same["branches_ours"] == same["branches_ref"] == 1
    assert same["open_ends_ours"] == 1 and same["endpoints_ref"] == 2
    moved = {**doc, "branches": [{"length": 12.0, "points": [[0, 0.25, 0], [12, 0.25, 0]],
                                  "radius": [1.5, 1.5]}]}
    fig = cl.compare(doc, moved)
    # the moved copy sticks out 2 past the end: Hausdorff = |(2, 0.25)| / h
    assert fig["hausdorff_h"] == pytest.approx(math.hypot(2, 0.25) / 0.5, rel=1e-9)
    assert fig["mean_ours_to_ref_h"] == pytest.approx(0.25 / 0.5, rel=1e-9)
    assert fig["mean_abs_radius_diff_h"] == pytest.approx(1.0, rel=1e-9)
    assert fig["length_ref"] == 12.0
