"""Self-tests of the reference oracle on synthetic meshes with known answers.

Run: reference/.venv/bin/python -m pytest -q reference
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
import oracle  # noqa: E402

ORACLE = Path(__file__).resolve().parent / "oracle.py"

# --------------------------------------------------------------------------------------------
# Synthetic meshes (outward-facing, counter-clockwise seen from outside)
# --------------------------------------------------------------------------------------------

CUBE_V = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
    dtype=np.float64,
)
CUBE_F = np.array(
    [
        [0, 2, 1], [0, 3, 2],  # z = 0 (bottom, normal -z)
        [4, 5, 6], [4, 6, 7],  # z = 1
        [0, 1, 5], [0, 5, 4],  # y = 0
        [2, 3, 7], [2, 7, 6],  # y = 1
        [1, 2, 6], [1, 6, 5],  # x = 1
        [0, 4, 7], [0, 7, 3],  # x = 0
    ],
    dtype=np.int64,
)  # fmt: skip


def icosphere(level: int, r: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    t = (1 + 5**0.5) / 2
    V = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]  # fmt: skip
    F = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]  # fmt: skip
    V = [np.array(v, float) / np.linalg.norm(v) for v in V]
    for _ in range(level):
        mid: dict[tuple[int, int], int] = {}

        def midpoint(a: int, b: int) -> int:
            key = (min(a, b), max(a, b))
            if key not in mid:
                m = V[a] + V[b]
                V.append(m / np.linalg.norm(m))
                mid[key] = len(V) - 1
            return mid[key]

        G = []
        for a, b, c in F:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            G += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        F = G
    return np.array(V) * r, np.array(F, dtype=np.int64)


def torus(R: float = 2.0, r: float = 0.5, n: int = 24, m: int = 12):
    u, v = np.meshgrid(np.arange(n) * 2 * np.pi / n, np.arange(m) * 2 * np.pi / m, indexing="ij")
    V = np.stack(
        [(R + r * np.cos(v)) * np.cos(u), (R + r * np.cos(v)) * np.sin(u), r * np.sin(v)], -1
    ).reshape(-1, 3)
    F = []
    for i in range(n):
        for j in range(m):
            a, b = i * m + j, ((i + 1) % n) * m + j
            c, d = ((i + 1) % n) * m + (j + 1) % m, i * m + (j + 1) % m
            F += [[a, b, c], [a, c, d]]
    return V, np.array(F, dtype=np.int64)


def signed_volume(V, F):
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6)


def write_ascii_stl(path: Path, V, F):
    lines = ["solid test"]
    for t in F:
        lines += ["facet normal 0 0 0", "outer loop"]
        lines += ["vertex %r %r %r" % tuple(map(float, V[i])) for i in t]
        lines += ["endloop", "endfacet"]
    lines.append("endsolid test")
    path.write_text("\n".join(lines) + "\n")


def write_soup_stl(path: Path, corners: np.ndarray):
    """Binary STL from an (F,3,3) array of triangle corners, written by hand with numpy."""
    rec = np.dtype([("n", "<f4", 3), ("v", "<f4", 9), ("attr", "<u2")])
    out = np.zeros(len(corners), dtype=rec)
    out["v"] = corners.reshape(-1, 9)
    path.write_bytes(b"\0" * 80 + np.uint32(len(corners)).tobytes() + out.tobytes())


@pytest.fixture(scope="module")
def sphere():
    return icosphere(4, r=2.0)  # 5120 triangles


# --------------------------------------------------------------------------------------------
# Loading
# --------------------------------------------------------------------------------------------


def test_stl_welds_exactly_equal_corners_only(tmp_path):
    corners = CUBE_V[CUBE_F].astype(np.float32)
    write_soup_stl(tmp_path / "cube.stl", corners)
    V, F = oracle.load_mesh(tmp_path / "cube.stl")
    assert V.shape == (8, 3) and F.shape == (12, 3)
    np.testing.assert_array_equal(V[F], CUBE_V[CUBE_F])
    # Nudge one corner by one float32 ulp: it must stay a separate vertex.
    nudged = corners.copy()
    nudged[3, 0, 0] = np.nextafter(nudged[3, 0, 0], np.float32(2))
    write_soup_stl(tmp_path / "nudged.stl", nudged)
    V2, F2 = oracle.load_mesh(tmp_path / "nudged.stl")
    assert V2.shape == (9, 3)
    res = oracle.check(V2, F2)
    assert res["manifold_status"] != "NoError"
    assert res["boundary_edges"] > 0 and not res["pymeshlab_watertight"]


def test_formats_agree(tmp_path, sphere):
    V, F = icosphere(1)
    V = V.astype(np.float32).astype(np.float64)  # exact in every format
    oracle.save_mesh(tmp_path / "s.stl", V, F)
    oracle.save_mesh(tmp_path / "s.obj", V, F)
    oracle.save_mesh(tmp_path / "s.ply", V, F)
    write_ascii_stl(tmp_path / "a.stl", V, F)
    for name in ("s.stl", "s.obj", "s.ply", "a.stl"):
        V2, F2 = oracle.load_mesh(tmp_path / name)
        assert V2.shape == V.shape and F2.shape == F.shape, name
        np.testing.assert_array_equal(V2[F2], V[F], err_msg=name)
    # OBJ keeps full float64 precision and unreferenced vertices.
    Vs, Fs = sphere
    Vx = np.vstack([Vs, [[9.0, 9.0, 9.0]]])
    oracle.save_mesh(tmp_path / "x.obj", Vx, Fs)
    V3, F3 = oracle.load_mesh(tmp_path / "x.obj")
    np.testing.assert_array_equal(V3, Vx)
    np.testing.assert_array_equal(F3, Fs)


def test_obj_quads_and_negative_indices(tmp_path):
    (tmp_path / "q.obj").write_text(
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1/1 2/2/2 3/3/3 4/4/4\nf -4 -2 -1\n"
    )
    V, F = oracle.load_mesh(tmp_path / "q.obj")
    assert V.shape == (4, 3)
    np.testing.assert_array_equal(F, [[0, 1, 2], [0, 2, 3], [0, 2, 3]])


def test_bad_files(tmp_path):
    (tmp_path / "short.stl").write_bytes(b"abc")
    with pytest.raises(oracle.OracleError):
        oracle.load_mesh(tmp_path / "short.stl")
    (tmp_path / "p.f64").write_bytes(b"\0" * 25)
    with pytest.raises(oracle.OracleError):
        oracle.read_points(tmp_path / "p.f64")
    with pytest.raises(oracle.OracleError):
        oracle.load_mesh(tmp_path / "missing.stl")


# --------------------------------------------------------------------------------------------
# Measures and watertightness
# --------------------------------------------------------------------------------------------


def test_unit_cube():
    res = oracle.check(CUBE_V, CUBE_F)
    assert res["manifold_status"] == "NoError"
    assert res["manifold_genus"] == 0
    assert res["manifold_volume"] == pytest.approx(1.0, abs=1e-12)
    assert res["pymeshlab_volume"] == pytest.approx(1.0, abs=1e-12)
    assert res["pymeshlab_area"] == pytest.approx(6.0, abs=1e-6)
    assert res["boundary_edges"] == 0 and res["pymeshlab_watertight"] is True
    assert (res["vertices"], res["faces"]) == (8, 12)
    inf = oracle.info(CUBE_V, CUBE_F)
    assert inf["volume"] == pytest.approx(1.0, abs=1e-12)
    assert inf["area"] == pytest.approx(6.0, abs=1e-12)
    assert inf["watertight"] is True and inf["boundary_loops"] == 0
    assert (inf["components"], inf["genus"], inf["non_manifold_edges"]) == (1, 0, 0)
    assert inf["bbox_min"] == [0, 0, 0] and inf["bbox_max"] == [1, 1, 1]


def test_inward_cube_keeps_its_sign():
    F = CUBE_F[:, ::-1].copy()
    res = oracle.check(CUBE_V, F)
    assert res["manifold_status"] == "NoError"
    assert res["manifold_volume"] == pytest.approx(-1.0, abs=1e-12)
    assert res["pymeshlab_volume"] == pytest.approx(1.0, abs=1e-12)  # absolute value
    assert oracle.info(CUBE_V, F)["volume"] == pytest.approx(-1.0, abs=1e-12)


def test_open_box():
    F = CUBE_F[2:]  # bottom removed
    res = oracle.check(CUBE_V, F)
    assert res["manifold_status"] != "NoError"
    assert res["manifold_genus"] is None and res["manifold_volume"] is None
    assert res["pymeshlab_watertight"] is False and res["pymeshlab_volume"] is None
    assert res["boundary_edges"] == 4
    assert res["pymeshlab_area"] == pytest.approx(5.0, abs=1e-6)
    inf = oracle.info(CUBE_V, F)
    assert inf["boundary_loops"] == 1 and inf["watertight"] is False and inf["volume"] is None


def test_triangle_soup_is_not_merged_by_manifold3d():
    V = CUBE_V[CUBE_F].reshape(-1, 3)
    F = np.arange(36, dtype=np.int64).reshape(12, 3)
    res = oracle.check(V, F)
    assert res["manifold_status"] == "NotManifold"
    assert res["boundary_edges"] == 36


def test_non_manifold_edge_and_components():
    # Two cubes sharing one edge (x=1, y=1): that edge has 4 triangles.
    V = np.vstack([CUBE_V, CUBE_V + [1, 1, 0]])
    F = np.vstack([CUBE_F, CUBE_F + 8])
    # Weld the shared edge: second cube's (0,0,z) corners are the first's (1,1,z) corners.
    F[F == 8] = 2
    F[F == 12] = 6
    for _ in range(5):  # repeatable (pymeshlab's own count is not)
        inf = oracle.info(V, F)
        assert inf["non_manifold_edges"] == 1 and inf["watertight"] is False
    assert inf["components"] == 1 and inf["boundary_loops"] is None and inf["genus"] is None
    res = oracle.check(V, F)
    assert res["pymeshlab_watertight"] is False and res["pymeshlab_volume"] is None
    # manifold3d pairs the four half-edges of the shared edge and accepts the solid: its
    # "NoError" does not mean "every edge has two triangles".
    assert res["manifold_status"] == "NoError"
    assert res["manifold_volume"] == pytest.approx(2.0, abs=1e-12)
    # Two disjoint cubes: two components, still watertight.
    inf2 = oracle.info(np.vstack([CUBE_V, CUBE_V + 5]), np.vstack([CUBE_F, CUBE_F + 8]))
    assert inf2["components"] == 2 and inf2["watertight"] is True
    assert inf2["volume"] == pytest.approx(2.0, abs=1e-12)


def test_icosphere_measures(sphere):
    V, F = sphere
    r = 2.0
    res = oracle.check(V, F)
    assert res["manifold_status"] == "NoError" and res["manifold_genus"] == 0
    exact = signed_volume(V, F)
    assert res["manifold_volume"] == pytest.approx(exact, rel=1e-9)
    assert res["pymeshlab_volume"] == pytest.approx(exact, rel=1e-9)
    assert res["pymeshlab_volume"] == pytest.approx(4 / 3 * math.pi * r**3, rel=5e-3)
    assert res["pymeshlab_area"] == pytest.approx(4 * math.pi * r**2, rel=5e-3)
    inf = oracle.info(V, F)
    assert inf["area"] == pytest.approx(res["pymeshlab_area"], rel=1e-6)
    assert inf["genus"] == 0


def test_torus_genus():
    V, F = torus()
    res = oracle.check(V, F)
    assert res["manifold_status"] == "NoError" and res["manifold_genus"] == 1
    assert oracle.info(V, F)["genus"] == 1


# --------------------------------------------------------------------------------------------
# Distance queries
# --------------------------------------------------------------------------------------------


def _directions(n, seed=0):
    d = np.random.default_rng(seed).normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def test_closest_on_icosphere(sphere):
    V, F = sphere
    r = 2.0
    sag = r * (1 - math.cos(0.08))  # > deviation of a level-4 icosphere from the sphere
    dirs = _directions(200)
    for R in (0.5, 1.5, 3.0, 5.0):
        res = oracle.closest(V, F, dirs * R)
        t = res["table"]
        assert res["n"] == 200 and t.shape == (200, 4)
        np.testing.assert_allclose(t[:, 0], abs(R - r), atol=sag)
        radius = np.linalg.norm(t[:, 1:], axis=1)
        assert np.all(radius <= r + 1e-12) and np.all(radius >= r - sag)
        # The closest point lies (nearly) on the query's ray, and is at the reported distance.
        cos = np.einsum("ij,ij->i", t[:, 1:] / radius[:, None], dirs)
        assert np.all(cos > 0.995)
        np.testing.assert_allclose(np.linalg.norm(t[:, 1:] - dirs * R, axis=1), t[:, 0], atol=1e-12)


def test_signed_distance_sign(sphere):
    V, F = sphere
    dirs = _directions(100, seed=1)
    inside = oracle.signed_distance(V, F, dirs * 1.0)["values"]
    outside = oracle.signed_distance(V, F, dirs * 3.0)["values"]
    assert np.all(inside < 0) and np.all(outside > 0)
    # Magnitude: the exact unsigned distance.
    np.testing.assert_allclose(np.abs(inside), oracle.closest(V, F, dirs)["table"][:, 0], rtol=1e-12)
    np.testing.assert_allclose(inside, -1.0, atol=0.01)
    np.testing.assert_allclose(outside, 1.0, atol=0.01)
    # libigl signs by 1 - 2|w|: an inward-facing sphere still has a negative inside.
    flipped = oracle.signed_distance(V, F[:, ::-1].copy(), dirs * 1.0)["values"]
    np.testing.assert_allclose(flipped, inside, rtol=1e-12)


def test_winding_number(sphere):
    V, F = sphere
    dirs = _directions(100, seed=2)
    # The fast winding number is an approximation (error ~1e-3 here); exact would be 1 and 0.
    np.testing.assert_allclose(oracle.winding(V, F, dirs * 1.0)["values"], 1.0, atol=5e-3)
    np.testing.assert_allclose(oracle.winding(V, F, dirs * 4.0)["values"], 0.0, atol=5e-3)
    # Orientation matters for the winding number itself: inward-facing gives -1 inside.
    w_in = oracle.winding(V, F[:, ::-1].copy(), dirs * 1.0)["values"]
    np.testing.assert_allclose(w_in, -1.0, atol=5e-3)
    # Open box without its bottom: from the centre the missing face subtends 1/6 of the sphere.
    w = oracle.winding(CUBE_V, CUBE_F[2:], np.array([[0.5, 0.5, 0.5]]))["values"][0]
    assert w == pytest.approx(5 / 6, abs=1e-3)


def test_hausdorff_shifted_cube():
    res = oracle.hausdorff(CUBE_V, CUBE_F, CUBE_V + [0.1, 0, 0], CUBE_F)
    assert res["hausdorff"] == pytest.approx(0.1, abs=1e-12)
    assert oracle.hausdorff(CUBE_V, CUBE_F, CUBE_V, CUBE_F)["hausdorff"] == 0.0


def test_close_holes_open_box():
    res = oracle.close_holes(CUBE_V, CUBE_F[2:])
    assert res["closed_holes"] == 1 and res["new_faces"] == 2
    assert res["faces"] == 12 and res["boundary_edges"] == 0 and res["holes_left"] == 0
    after = oracle.check(res["V"], res["F"])
    assert after["manifold_status"] == "NoError"
    assert after["manifold_volume"] == pytest.approx(1.0, abs=1e-12)
    # A hole larger than the limit is left open.
    assert oracle.close_holes(CUBE_V, CUBE_F[2:], max_hole_size=3)["boundary_edges"] == 4


# --------------------------------------------------------------------------------------------
# CLI round trip
# --------------------------------------------------------------------------------------------


def run_cli(*args, ok=True):
    p = subprocess.run(
        [sys.executable, str(ORACLE), *map(str, args)], capture_output=True, text=True, timeout=120
    )
    if not ok:
        assert p.returncode == 1, p.stderr
        assert p.stdout == "" and "error" in p.stderr
        return None
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    assert len(lines) == 1, p.stdout  # exactly one JSON object on stdout
    out = json.loads(lines[0])
    assert isinstance(out["seconds"], float) and out["seconds"] >= 0
    return out


def test_cli_round_trip(tmp_path, sphere):
    V, F = sphere
    mesh = tmp_path / "sphere.obj"
    oracle.save_mesh(mesh, V, F)
    cube = tmp_path / "cube.stl"
    oracle.save_mesh(cube, CUBE_V, CUBE_F)
    shifted = tmp_path / "shifted.obj"
    oracle.save_mesh(shifted, CUBE_V + [0.1, 0, 0], CUBE_F)
    open_box = tmp_path / "open.stl"
    oracle.save_mesh(open_box, CUBE_V, CUBE_F[2:])

    dirs = _directions(50, seed=3)
    pts = np.vstack([dirs * 1.0, dirs * 3.0])
    pfile = tmp_path / "p.f64"
    pfile.write_bytes(pts.astype("<f8").tobytes())

    out = run_cli("check", cube)
    assert out["manifold_status"] == "NoError" and out["pymeshlab_watertight"] is True
    assert out["pymeshlab_volume"] == pytest.approx(1.0, abs=1e-12)
    out = run_cli("check", open_box)
    assert out["manifold_status"] == "NotManifold" and out["manifold_genus"] is None
    out = run_cli("info", cube)
    assert out["volume"] == pytest.approx(1.0) and out["bbox_max"] == [1.0, 1.0, 1.0]
    expected_info = {"vertices", "faces", "components", "boundary_loops", "non_manifold_edges",
                     "watertight", "volume", "area", "bbox_min", "bbox_max", "genus", "seconds"}  # fmt: skip
    assert set(out) == expected_info

    out = run_cli("closest", mesh, pfile, tmp_path / "c.f64")
    assert out["n"] == 100
    c = np.fromfile(tmp_path / "c.f64", dtype="<f8").reshape(-1, 4)
    np.testing.assert_array_equal(c, oracle.closest(V, F, pts)["table"])

    out = run_cli("signed_distance", mesh, pfile, tmp_path / "s.f64")
    s = np.fromfile(tmp_path / "s.f64", dtype="<f8")
    assert out["n"] == 100 and s.shape == (100,)
    assert np.all(s[:50] < 0) and np.all(s[50:] > 0)

    out = run_cli("winding", mesh, pfile, tmp_path / "w.f64")
    w = np.fromfile(tmp_path / "w.f64", dtype="<f8")
    np.testing.assert_allclose(w, np.r_[np.ones(50), np.zeros(50)], atol=5e-3)

    out = run_cli("hausdorff", cube, shifted)
    assert out["hausdorff"] == pytest.approx(0.1, abs=1e-7)  # the STL cube is float32

    out = run_cli("close_holes", open_box, tmp_path / "closed.ply")
    assert out["closed_holes"] == 1 and out["faces"] == 12
    assert run_cli("check", tmp_path / "closed.ply")["manifold_status"] == "NoError"

    # Errors: exit 1, message on stderr, nothing on stdout.
    run_cli("check", tmp_path / "missing.stl", ok=False)
    run_cli("closest", mesh, tmp_path / "missing.f64", tmp_path / "x.f64", ok=False)
    run_cli("nonsense", ok=False)


def test_marching_cubes_sphere(tmp_path):
    """libigl's marching cubes of a sphere's signed distance: closed, outward, near 4/3·π r³."""
    n, h, o = 41, 0.065, -1.3
    k, j, i = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
    P = np.stack([i, j, k], -1).reshape(-1, 3) * h + o
    S = np.linalg.norm(P, axis=1) - 1.0
    res = oracle.marching_cubes(S, (n, n, n), (o, o, o), h)
    chk = oracle.check(res["V"], res["F"])
    assert chk["manifold_status"] == "NoError"
    assert chk["manifold_volume"] == pytest.approx(4 / 3 * math.pi, rel=5e-3)
    S.astype("<f8").tofile(tmp_path / "g.f64")
    out = run_cli("marching_cubes", tmp_path / "g.f64", n, n, n, o, o, o, h, tmp_path / "mc.ply")
    assert (out["vertices"], out["faces"]) == (len(res["V"]), len(res["F"]))
    V, F = oracle.load_mesh(tmp_path / "mc.ply")
    np.testing.assert_array_equal(F, res["F"])
    # Errors: wrong size, bad voxel.
    grid, bad = tmp_path / "g.f64", tmp_path / "x.ply"
    run_cli("marching_cubes", grid, n, n, n + 1, o, o, o, h, bad, ok=False)
    run_cli("marching_cubes", grid, n, n, n, o, o, o, 0, bad, ok=False)


# --------------------------------------------------------------------------------------------
# Real meshes (../shared/data/real, figures from its SOURCES.md)
# --------------------------------------------------------------------------------------------

REAL = Path(__file__).resolve().parent.parent.parent / "shared" / "data" / "real"
REAL_FIGURES = {  # file: (V, F, closed, boundary loops)
    "aorta_abdominal_open_ends.stl": (6068, 11887, False, 3),
    "aorta_abdominal_capped.stl": (6468, 12932, True, 0),
    "carotid_bifurcation.stl": (5829, 11594, False, 3),
    "ica_aneurysm_c0015.stl": (3862, 7485, False, 3),
    "coronary_stenosis_xray.stl": (3232, 6400, False, 2),
    "cortex_rh_pial_fsaverage5.stl": (10242, 20480, True, 0),
}


@pytest.mark.parametrize("name", sorted(REAL_FIGURES))
def test_real_meshes_match_sources(name):
    if not REAL.is_dir():
        pytest.skip("skipping: ../shared/data/real not found")
    V, F = oracle.load_mesh(REAL / name)
    nv, nf, closed, loops = REAL_FIGURES[name]
    inf = oracle.info(V, F)
    assert (inf["vertices"], inf["faces"]) == (nv, nf)
    assert inf["watertight"] is closed and inf["boundary_loops"] == loops
    assert inf["components"] == 1 and inf["non_manifold_edges"] == 0
    res = oracle.check(V, F)
    assert (res["manifold_status"] == "NoError") is closed
    if closed:
        # Two libraries agree on the enclosed volume; the capped aorta faces inward.
        assert res["manifold_volume"] == pytest.approx(inf["volume"], rel=1e-9)
        assert (inf["volume"] < 0) is name.startswith("aorta")


# --------------------------------------------------------------------------------------------
# Diffusion and threshold dynamics (grids as vesselmsr .npy + sidecar)
# --------------------------------------------------------------------------------------------


def _sidecar(dims, voxel, origin=(0.0, 0.0, 0.0)):
    return {"dims": list(dims), "origin": list(origin), "voxel": voxel, "axis_order": "z,y,x",
            "units": "file units", "sign": "negative inside"}  # fmt: skip


def _reflect_filter(a: np.ndarray, sigma: float, truncate: float = 4.0) -> np.ndarray:
    """Independent of scipy: mirror-pad (… c b a | a b c …) and convolve each axis with the
    normalised sampled Gaussian, in float64."""
    r = int(truncate * sigma + 0.5)
    w = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    w /= w.sum()
    out = a.astype(np.float64)
    for axis in range(3):
        n = out.shape[axis]
        idx = np.arange(-r, n + r) % (2 * n)
        idx = np.where(idx < n, idx, 2 * n - 1 - idx)
        padded = np.take(out, idx, axis=axis)
        out = np.apply_along_axis(lambda v: np.convolve(v, w, mode="valid"), axis, padded)
    return out


def test_gaussian_matches_mirror_convolution_and_moments():
    rng = np.random.default_rng(5)
    a = rng.standard_normal((9, 12, 15)).astype(np.float32)
    h, t = 0.5, 0.5  # σ = √(2t)/h = 2 voxels: the kernel (r = 8) folds over the 9-node axis
    res = oracle.gaussian(a, h, t)
    assert res["sigma_voxels"] == pytest.approx(2.0)
    assert res["values"].dtype == np.float32
    np.testing.assert_allclose(res["values"], _reflect_filter(a, 2.0), atol=2e-6)
    # Constant fields stay constant; a delta spreads to variance σ² per axis (mass kept).
    c = oracle.gaussian(np.full((7, 8, 9), 2.5, np.float32), 1.0, 3.0)["values"]
    np.testing.assert_allclose(c, 2.5, rtol=1e-6)
    d = np.zeros((41, 41, 41), np.float32)
    d[20, 20, 20] = 1
    g = oracle.gaussian(d, 1.0, 4.5)["values"].astype(np.float64)  # σ = 3
    x = np.arange(41) - 20
    assert g.sum() == pytest.approx(1.0, rel=1e-5)
    for axis in range(3):
        m = g.sum(axis=tuple(b for b in range(3) if b != axis))
        assert (m * x**2).sum() == pytest.approx(9.0, rel=2e-3)
    with pytest.raises(oracle.OracleError):
        oracle.gaussian(a, h, 0.0)


def _sphere_sdf(n: int, h: float, r: float) -> np.ndarray:
    c = (n - 1) / 2
    k, j, i = np.meshgrid(*(np.arange(n),) * 3, indexing="ij")
    return ((np.sqrt((i - c) ** 2 + (j - c) ** 2 + (k - c) ** 2) * h) - r).astype(np.float32)


def test_mbo_step_sphere():
    """One step on a sphere of radius R: mcf shrinks it to about √(R² − 4dt) (the grid's binary
    threshold quantises to a voxel), vpmcf keeps its node count; φ_new is a signed distance."""
    n, h, R, dt = 48, 0.5, 8.0, 2.0
    phi = _sphere_sdf(n, h, R)
    res = oracle.mbo_step(phi.astype(np.float64), h, dt, "mcf")
    new = res["values"]
    vol = res["inside_after"] * h**3
    r_new = (3 * vol / (4 * math.pi)) ** (1 / 3)
    assert r_new == pytest.approx(math.sqrt(R * R - 4 * dt), abs=h)
    assert r_new < R - 0.5 * h
    assert res["shift"] == 0.0 and np.count_nonzero(new < 0) == res["inside_after"]
    # Distances: the centre is about r_new deep, a corner about its distance to the sphere.
    assert -new[24, 24, 24] == pytest.approx(r_new, abs=h)
    assert new[0, 0, 0] == pytest.approx(math.sqrt(3) * 23.5 * h - r_new, abs=h)
    vp = oracle.mbo_step(phi.astype(np.float64), h, dt, "vpmcf")
    assert vp["inside_after"] == vp["inside_before"] == np.count_nonzero(phi < 0)
    assert vp["shift"] > 0  # the smoothed field of a convex shape must be lowered less
    with pytest.raises(oracle.OracleError):
        oracle.mbo_step(phi, h, -1.0)
    with pytest.raises(oracle.OracleError):
        oracle.mbo_step(phi, h, 1.0, "expand")


def test_gaussian_and_mbo_cli(tmp_path):
    rng = np.random.default_rng(6)
    a = rng.standard_normal((6, 7, 8)).astype(np.float32)
    side = _sidecar((8, 7, 6), 0.25, (1.0, -2.0, 0.5))
    grid = tmp_path / "g.npy"
    oracle.write_npy_grid(grid, a, side)
    out = run_cli("gaussian", grid, 0.0625, tmp_path / "o.npy", "--truncate", 3)
    assert out["sigma_voxels"] == pytest.approx(1.414213562373095)
    o, o_side = oracle.read_npy_grid(tmp_path / "o.npy")
    assert o_side == side
    np.testing.assert_array_equal(o, oracle.gaussian(a, 0.25, 0.0625, truncate=3)["values"])
    phi = _sphere_sdf(20, 0.5, 3.0)
    oracle.write_npy_grid(tmp_path / "s.npy", phi, _sidecar((20, 20, 20), 0.5))
    out = run_cli("mbo_step", tmp_path / "s.npy", 0.5, tmp_path / "m.npy", "--velocity", "vpmcf")
    m, _ = oracle.read_npy_grid(tmp_path / "m.npy")
    assert out["inside_after"] == out["inside_before"] == np.count_nonzero(m < 0)
    # Errors: bad time, missing sidecar, sidecar disagreeing with the array.
    run_cli("gaussian", grid, 0, tmp_path / "x.npy", ok=False)
    np.save(tmp_path / "bare.npy", a)
    run_cli("gaussian", tmp_path / "bare.npy", 1, tmp_path / "x.npy", ok=False)
    oracle.write_npy_grid(tmp_path / "bad.npy", a, _sidecar((8, 7, 5), 0.25))
    run_cli("mbo_step", tmp_path / "bad.npy", 1, tmp_path / "x.npy", ok=False)
