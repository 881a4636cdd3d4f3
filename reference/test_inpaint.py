"""Tests of the reference axial inpainting (reference/inpaint.py) on a straight capped tube whose
wall is dented by a carved ball: the filled φ's volume in D matches the intact tube's.

Run: reference/.venv/bin/python -m pytest -q reference/test_inpaint.py
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import inpaint  # noqa: E402
import oracle  # noqa: E402

SCRIPT = Path(__file__).resolve().parent / "inpaint.py"
R = 3.0
LENGTH = 30.0
DENT = 1.2 * R  # radius of the carved ball, centred on the wall at (R, 0, 0)
D = np.array([[R, 0.0, 0.0, 2.0 * R]])  # the region: covers the dent with a margin


def capped_tube(segments=96, rings=121, dent=True):
    """Closed outward tube of radius R around the z axis, z in [−L/2, L/2], flat fan caps; with
    `dent`, the wall vertices inside the ball of radius DENT at (R, 0, 0) are moved radially
    inward onto that ball's sphere (the solid inside the ball carved out, kept ≥ 0.15R)."""
    th = 2 * math.pi * np.arange(segments) / segments
    z = np.linspace(-LENGTH / 2, LENGTH / 2, rings)
    T, Z = np.meshgrid(th, z)
    rho = np.full(T.shape, R)
    if dent:
        disc = DENT**2 - (R * np.sin(T)) ** 2 - Z**2
        inside = (R * np.cos(T) - R) ** 2 + (R * np.sin(T)) ** 2 + Z**2 < DENT**2
        carved = R * np.cos(T) - np.sqrt(np.maximum(disc, 0.0))
        rho = np.where(inside, np.maximum(carved, 0.15 * R), rho)
    V = np.stack([(rho * np.cos(T)).ravel(), (rho * np.sin(T)).ravel(), Z.ravel()], 1)
    F = []
    for j in range(rings - 1):
        for i in range(segments):
            a, b = j * segments + i, j * segments + (i + 1) % segments
            F += [[a, b, b + segments], [a, b + segments, a + segments]]
    bottom, top = len(V), len(V) + 1
    V = np.vstack([V, [[0, 0, -LENGTH / 2], [0, 0, LENGTH / 2]]])
    last = (rings - 1) * segments
    for i in range(segments):
        F.append([bottom, (i + 1) % segments, i])
        F.append([top, last + i, last + (i + 1) % segments])
    return V, np.array(F, np.int64)


def truth_volume(h):
    """Volume in D of the intact tube (analytic ρ < R) on the quadrature points of
    inpaint.volume_in_D."""
    step = h / inpaint.SUPERSAMPLE
    lo = D[0, :3] - D[0, 3]
    hi = D[0, :3] + D[0, 3]
    ax = [np.arange(lo[a] + 0.5 * step, hi[a], step) for a in range(3)]
    X, Y, Z = np.meshgrid(*ax, indexing="ij")
    P = np.stack([X.ravel(), Y.ravel(), Z.ravel()], 1)
    P = P[inpaint.depth_of(P, D)[0] > 0]
    return np.count_nonzero(np.hypot(P[:, 0], P[:, 1]) < R) * step**3


def test_tube_is_closed_and_outward():
    V, F = capped_tube()
    c = oracle.check(V, F)
    assert c["manifold_status"] == "NoError"
    assert c["boundary_edges"] == 0
    assert c["manifold_volume"] > 0


def test_axis_is_the_tube_axis():
    V, F = capped_tube()
    a = inpaint.estimate_axis(V, F, D[0])
    assert abs(abs(a[2]) - 1.0) < 1e-3


def test_sub_box_matches_repair_rule():
    V, F = capped_tube()
    h = 0.25
    origin, dims = inpaint.sub_box(V, F, D, h)
    # The box spans the ball plus the axial margin 6h on every side, on the mesh's lattice.
    margin = 6 * h
    assert np.all(origin <= D[0, :3] - D[0, 3] - margin + 1e-9)
    assert np.all(origin + (dims - 1) * h >= D[0, :3] + D[0, 3] + margin - 1e-9)
    assert np.all(origin > D[0, :3] - D[0, 3] - margin - h - 1e-9)
    lo = V.min(0) - (4 * h + margin + 2 * D[0, 3])
    k = (origin - lo) / h
    assert np.allclose(k, np.round(k), atol=1e-9)


def test_filled_volume_in_D_within_3_percent_of_truth():
    V, F = capped_tube()
    h = R / 8
    res, psi = inpaint.inpaint(V, F, D, voxel=h)
    truth = truth_volume(h)
    damaged = res["volume_in_D_of_phi0"]
    filled = res["volume_in_D_of_filled_phi"]
    assert abs(damaged - truth) / truth > 0.10, (damaged, truth)  # the dent is real
    assert abs(filled - truth) / truth < 0.03, (filled, truth)
    assert psi.shape == tuple(res["dims"])
    # Outside D the field is φ_0 (libigl signed distance): the tube's distance far from the dent.
    p = np.array(res["origin"])
    assert abs(psi[0, 0, 0] - (np.hypot(p[0], p[1]) - R)) < 0.01 * R


def test_intact_tube_is_left_as_it_is():
    V, F = capped_tube(dent=False)
    res, _ = inpaint.inpaint(V, F, D, voxel=R / 8)
    assert (
        abs(res["volume_in_D_of_filled_phi"] - res["volume_in_D_of_phi0"])
        / res["volume_in_D_of_phi0"]
        < 0.01
    )


def test_cli_prints_json(tmp_path):
    V, F = capped_tube()
    mesh = tmp_path / "tube.stl"
    oracle.save_mesh(mesh, V, F)
    out = tmp_path / "phi.f64"
    r = subprocess.run(
        [sys.executable, str(SCRIPT), str(mesh), "--region", "3,0,0,6", "--voxel", "0.5",
         "--out", str(out)],
        capture_output=True,
        text=True,
        check=True,
    )
    res = json.loads(r.stdout)
    for key in ("seconds", "voxel", "dims", "volume_in_D_of_filled_phi", "volume_in_D_of_phi0"):
        assert key in res
    assert res["voxel"] == 0.5
    assert out.stat().st_size == 8 * math.prod(res["dims"])


@pytest.mark.parametrize("args", [["missing.stl", "--region", "0,0,0,1"], ["x.stl"]])
def test_cli_bad_input_exits_nonzero(args, tmp_path):
    r = subprocess.run(
        [sys.executable, str(SCRIPT), *args], capture_output=True, text=True, cwd=tmp_path
    )
    assert r.returncode != 0
    assert r.stdout == ""
