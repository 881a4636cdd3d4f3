"""Tests of reference/msr.py on a small sphere (fast)."""

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import msr  # noqa: E402
import oracle  # noqa: E402

N, H, R = 40, 0.5, 6.0
ORIGIN = np.array([-10.0, -9.5, -10.25])
CENTRE = ORIGIN + H * np.array([19.6, 20.3, 19.1])


def _sphere():
    k, j, i = np.meshgrid(np.arange(N), np.arange(N), np.arange(N), indexing="ij")
    p = np.stack([i, j, k], axis=-1) * H + ORIGIN
    return np.linalg.norm(p - CENTRE, axis=-1) - R


def _samples(n=400, seed=3):
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(n, 3))
    return CENTRE + R * d / np.linalg.norm(d, axis=1, keepdims=True)


def test_projection_lands_on_the_sphere():
    interp = msr.Interpolant(_sphere(), ORIGIN, H)
    rng = np.random.default_rng(1)
    d = rng.normal(size=(200, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    start = CENTRE + d * (R + rng.uniform(-1.5, 1.5, size=(200, 1)))
    x, bad = msr.project(interp, start)
    assert bad == 0
    assert np.allclose(np.linalg.norm(x - CENTRE, axis=1), R, atol=0.01 * H)
    # Orthogonal: the point moved along the radius.
    assert np.allclose((x - CENTRE) / R, d, atol=1e-3)


def test_decompose_sphere_keeps_volume_and_details_are_small():
    phi = _sphere()
    d = msr.decompose(phi, ORIGIN, H, _samples(), 2 * H * H, 2, 3)
    assert len(d["mean_abs_detail"]) == 3 and d["unconverged"] == [0, 0, 0]
    # Samples added before each level: X_{i−1}, n_{i−1} and W_i agree in length.
    assert len(d["samples"][0]) > 400
    for i in range(3):
        assert len(d["samples"][i]) == len(d["normals"][i]) == len(d["details"][i])
        assert len(d["samples"][i + 1]) >= len(d["samples"][i])
    inside0 = np.count_nonzero(phi < 0)
    for p in d["phis"][1:]:
        assert np.count_nonzero(p < 0) == inside0  # vpmcf keeps the node count
    # A sphere under volume-preserving flow stays put: details stay under a voxel.
    assert max(d["mean_abs_detail"]) < H
    r = np.linalg.norm(d["samples"][-1] - CENTRE, axis=1)
    assert abs(r.mean() - R) < H


def test_cover_gaps_leaves_no_marching_cubes_vertex_uncovered():
    from scipy.spatial import cKDTree

    phi = _sphere()
    interp = msr.Interpolant(phi, ORIGIN, H)
    samples, _ = msr.project(interp, _samples(100))
    radius = 0.5 * H
    new = msr.cover_gaps(phi, ORIGIN, H, interp, samples, radius)
    assert len(new) > 100
    # On the sphere, and no two new samples nearer than the radius (greedy) before projection
    # moved them by well under a voxel.
    assert np.allclose(np.linalg.norm(new - CENTRE, axis=1), R, atol=0.01 * H)
    V = oracle.marching_cubes(phi.ravel(), (N, N, N), tuple(ORIGIN), H)["V"]
    d, _ = cKDTree(np.concatenate([samples, new])).query(V)
    # Every vertex had a sample within the radius before projection, which moves the new ones
    # by the marching-cubes chord error (a few hundredths of a voxel on this sphere).
    assert d.max() <= radius + 0.05 * H
    # Nothing to add where the samples already cover the surface.
    assert len(msr.cover_gaps(phi, ORIGIN, H, interp, np.concatenate([samples, new]), 2 * radius)) == 0


def test_rebuild_gives_back_the_finer_level():
    phi = _sphere()
    d = msr.decompose(phi, ORIGIN, H, _samples(2000), 2 * H * H, 2, 2)
    rebuilt = msr.rebuild_from_tangent_planes(
        d["phis"][1], ORIGIN, H, d["samples"][0], d["normals"][0], d["details"][0]
    )
    flipped = np.count_nonzero((rebuilt < 0) != (d["phis"][0] < 0))
    assert flipped < 0.01 * np.count_nonzero(phi < 0)
    # Near the surface the rebuilt distances match the true ones to about a voxel.
    band = np.abs(d["phis"][0]) < 2 * H
    assert np.mean(np.abs(rebuilt - d["phis"][0])[band]) < 0.5 * H


def test_cli(tmp_path):
    grid = tmp_path / "phi.npy"
    side = {"dims": [N, N, N], "origin": ORIGIN.tolist(), "voxel": H}
    oracle.write_npy_grid(grid, _sphere(), side)
    pts = tmp_path / "points.f64"
    oracle.write_f64(pts, _samples())
    out = subprocess.run(
        [sys.executable, str(Path(msr.__file__)), str(grid), str(pts), str(2 * H * H), "2", "2"],
        capture_output=True,
        text=True,
        check=True,
    )
    res = json.loads(out.stdout)
    assert len(res["mean_abs_detail"]) == 2 and res["seconds"] > 0 and res["samples"] == 400
    assert res["samples_final"] > 400 and 0 < res["cover_seconds"] < res["decompose_seconds"]
    none = subprocess.run(
        [sys.executable, str(Path(msr.__file__)), str(grid), str(pts), str(2 * H * H), "2", "2", "0"],
        capture_output=True,
        text=True,
        check=True,
    )
    assert json.loads(none.stdout)["samples_final"] == 400
    assert all(math.isfinite(v) for v in res["rebuild_mean_abs_error_h"])
    bad = subprocess.run([sys.executable, str(Path(msr.__file__)), str(grid)], capture_output=True)
    assert bad.returncode == 1
    bad = subprocess.run(
        [sys.executable, str(Path(msr.__file__)), str(grid), str(pts), "0.5", "2", "2", "-1"], capture_output=True
    )
    assert bad.returncode == 1
