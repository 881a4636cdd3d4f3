"""Tests of the pymeshlab baselines (reference/baseline.py) on synthetic meshes with known answers.

Run: reference/.venv/bin/python -m pytest -q reference/test_baseline.py
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
import baseline  # noqa: E402
import oracle  # noqa: E402

BASELINE = Path(__file__).resolve().parent / "baseline.py"


def open_tube(radius=3.0, length=30.0, segments=32, rings=31):
    """Open tube around the z axis, outward-facing, two boundary loops (the ends)."""
    th = 2 * math.pi * np.arange(segments) / segments
    z = np.linspace(0.0, length, rings)
    V = np.array([[radius * math.cos(t), radius * math.sin(t), zz] for zz in z for t in th])
    F = []
    for j in range(rings - 1):
        for i in range(segments):
            a, b = j * segments + i, j * segments + (i + 1) % segments
            c, d = b + segments, a + segments
            F += [[a, b, c], [a, c, d]]
    return V, np.array(F, np.int64)


def icosphere(subdivisions=3, radius=1.0):
    """Outward-facing icosphere."""
    t = (1 + 5**0.5) / 2
    V = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t],
         [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]  # fmt: skip
    F = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]  # fmt: skip
    V = [np.array(v, float) / np.linalg.norm(v) for v in V]
    for _ in range(subdivisions):
        mid = {}

        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = V[a] + V[b]
                V.append(p / np.linalg.norm(p))
                mid[key] = len(V) - 1
            return mid[key]

        F = [
            f
            for a, b, c in F
            for f in ([a, m(a, b), m(c, a)], [b, m(b, c), m(a, b)], [c, m(c, a), m(b, c)],
                      [m(a, b), m(b, c), m(c, a)])  # fmt: skip
        ]
    return radius * np.array(V), np.array(F, np.int64)


def tube_with_hole():
    """The open tube with the faces within 1.5 of (0, 3, 15) removed: 3 boundary loops."""
    V, F = open_tube()
    near = np.linalg.norm(V - np.array([0.0, 3.0, 15.0]), axis=1) <= 1.5
    return V, F[~near[F].all(axis=1)]


def loops(V, F):
    return baseline._loops(baseline._meshset(V, F))


def test_close_holes_closes_a_wall_hole(tmp_path):
    V, F = tube_with_hole()
    assert loops(V, F) == 3
    src, out = tmp_path / "in.ply", tmp_path / "out.ply"
    oracle.save_mesh(src, V, F)
    res = baseline.close_holes(src, out)
    assert res["boundary_loops_in"] == 3
    assert res["boundary_loops"] < 3
    assert res["maxholesize"] == res["boundary_edges_in"] + 1
    V2, F2 = oracle.load_mesh(out)
    assert len(F2) == res["faces"] > len(F)
    # With a size limit below the ends (32 edges) only the wall hole is closed.
    res = baseline.close_holes(src, out, maxholesize=30)
    assert res["boundary_loops"] == 2
    assert not res["watertight"]


def test_close_holes_on_closed_tube_ends_is_watertight(tmp_path):
    V, F = open_tube()
    src, out = tmp_path / "in.ply", tmp_path / "out.ply"
    oracle.save_mesh(src, V, F)
    res = baseline.close_holes(src, out)
    assert res["boundary_loops"] == 0
    assert res["watertight"]
    # Volume of the polygonal cylinder: (segments/2)·r²·sin(2π/segments)·length.
    exact = 16 * 9.0 * math.sin(2 * math.pi / 32) * 30.0
    assert abs(res["volume"] - exact) / exact < 1e-6


def test_poisson_sphere_is_watertight_with_the_right_volume(tmp_path):
    V, F = icosphere(3, radius=2.0)
    src, out = tmp_path / "sphere.ply", tmp_path / "poisson.ply"
    oracle.save_mesh(src, V, F)
    res = baseline.poisson(src, out, depth=6)
    exact = 4 / 3 * math.pi * 2.0**3
    print(res)
    assert res["watertight"], res["manifold_status"]
    assert abs(res["volume"] - exact) / exact < 0.10
    assert res["points"] == len(V)


def test_cli_prints_json_keys(tmp_path):
    V, F = tube_with_hole()
    src = tmp_path / "in.ply"
    oracle.save_mesh(src, V, F)
    for cmd, extra in (("close-holes", []), ("poisson", ["--depth", "5"])):
        out = tmp_path / f"{cmd}.stl"
        run = subprocess.run(
            [sys.executable, str(BASELINE), cmd, str(src), str(out), *extra],
            capture_output=True,
            text=True,
        )
        assert run.returncode == 0, run.stderr
        res = json.loads(run.stdout)
        for key in ("method", "seconds", "volume", "watertight", "vertices", "faces",
                    "boundary_loops_in", "boundary_loops", "manifold_status"):  # fmt: skip
            assert key in res, (cmd, key)
        assert res["method"] == cmd
        assert out.exists()


@pytest.mark.parametrize("cmd", ["close-holes", "poisson"])
def test_cli_bad_input_fails_with_a_message(tmp_path, cmd):
    missing = tmp_path / "missing.stl"
    run = subprocess.run(
        [sys.executable, str(BASELINE), cmd, str(missing), str(tmp_path / "o.stl")],
        capture_output=True,
        text=True,
    )
    assert run.returncode != 0
    assert "missing.stl" in run.stderr
    assert run.stdout == ""
    bad = tmp_path / "bad.xyz"
    bad.write_text("nothing")
    run = subprocess.run(
        [sys.executable, str(BASELINE), cmd, str(bad), str(tmp_path / "o.stl")],
        capture_output=True,
        text=True,
    )
    assert run.returncode != 0 and "unknown mesh extension" in run.stderr
