"""Reference multiscale representation (MSR) in numpy/scipy, for benchmarking `vesselmsr`'s
decompose + tangent-plane rebuild (issue 5) on the same input.

The algorithm follows Dong, Chien, Shen and Osher (level-set multiscale representation), as
`src/msr/decompose.rs` and `src/msr/reconstruct.rs` do, written plainly with scipy:

* φ_0 (a voxelized signed distance, .npy + sidecar as `vesselmsr::io::write_npy` writes it) is
  redistanced with `distance_transform_edt`;
* each of the N levels runs `steps` volume-keeping threshold-dynamics steps (oracle.mbo_step
  "vpmcf": gaussian_filter, bisection of the threshold shift, distance_transform_edt);
* the samples X_{i−1} are projected onto the zero level set of φ_i by Newton steps
  x ← x − φ ∇φ/|∇φ|² (step at most `max_step` voxels), with φ and ∇φ interpolated by
  `scipy.ndimage.map_coordinates` (order 3); W_i = X_i − X_{i−1}, w_i = W_i·n_i with
  n_i = ∇φ_i/|∇φ_i| at X_i;
* the input samples are first snapped onto the zero level set of φ_0 the same way;
* before each level i, samples are added where S_{i−1} has none (`cover_gaps`, as
  `src/msr/cover.rs`): every vertex of the marching-cubes surface of φ_{i−1} (libigl
  `marching_cubes`) with no sample within `cover` voxels (default 0.25, vesselmsr's default
  `cover_radius`) becomes one, greedily in vertex order (a new one covers the vertices after
  it), Newton-projected onto S_{i−1}, those that do not converge dropped; they join X_{i−1}
  with their normals n_{i−1} and are tracked from level i on;
* each φ_{i−1} is then rebuilt from φ_i and (X_{i−1}, n_{i−1}, W_i): near the samples a node
  takes the Gaussian-weighted (σ = h/4, relative to the nearest) mean over its 8 nearest samples
  (`scipy.spatial.cKDTree`) of its signed distance to their tangent planes, its magnitude kept
  within [d_min − `coverage`, d_min] (d_min: the nearest sample's distance); elsewhere the side
  of φ_i (at least `band_margin` voxels from the surface); then distance_transform_edt.

CLI: `python msr.py PHI.npy POINTS.f64 DT STEPS LEVELS [COVER]` (COVER in voxels, 0: no added
samples) prints one JSON line with "seconds" (decompose + rebuilds, no I/O),
"decompose_seconds", "cover_seconds" (the added samples, within decompose), "rebuild_seconds",
"mean_abs_detail" (per level, world units), "samples" (the input's), "samples_final" (with the
added ones), "unconverged" (per level).
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import oracle  # noqa: E402


class Interpolant:
    """Cubic-spline interpolation of φ and of its central-difference gradient on a grid of
    voxel `voxel` whose node (0, 0, 0) is at `origin`; arrays are indexed [k, j, i]."""

    def __init__(self, phi: np.ndarray, origin: np.ndarray, voxel: float):
        from scipy import ndimage

        self.origin = np.asarray(origin, np.float64)
        self.voxel = float(voxel)
        self.coef = ndimage.spline_filter(phi, order=3, mode="nearest")
        # np.gradient over axes (z, y, x): reorder to (x, y, z) world components.
        gz, gy, gx = np.gradient(phi, self.voxel)
        self.gcoef = [ndimage.spline_filter(g, order=3, mode="nearest") for g in (gx, gy, gz)]

    def _coords(self, pts: np.ndarray) -> np.ndarray:
        q = (pts - self.origin) / self.voxel
        return q[:, ::-1].T  # (z, y, x) rows

    def value(self, pts: np.ndarray) -> np.ndarray:
        from scipy import ndimage

        return ndimage.map_coordinates(self.coef, self._coords(pts), order=3, mode="nearest", prefilter=False)

    def gradient(self, pts: np.ndarray) -> np.ndarray:
        from scipy import ndimage

        c = self._coords(pts)
        return np.stack(
            [ndimage.map_coordinates(g, c, order=3, mode="nearest", prefilter=False) for g in self.gcoef],
            axis=1,
        )


def unit_normals(interp: Interpolant, pts: np.ndarray) -> np.ndarray:
    g = interp.gradient(pts)
    n = np.linalg.norm(g, axis=1, keepdims=True)
    return np.where(n > 1e-12, g / np.maximum(n, 1e-300), 0.0)


def project(
    interp: Interpolant, pts: np.ndarray, tolerance: float = 1e-3, max_iterations: int = 30, max_step: float = 2.0
) -> tuple[np.ndarray, int]:
    """Newton projection of `pts` onto the zero level set (tolerance and step in voxels); the
    projected points and how many did not reach |φ| ≤ tolerance·h."""
    h = interp.voxel
    x = pts.copy()
    active = np.arange(len(x))
    for _ in range(max_iterations):
        if active.size == 0:
            break
        p = x[active]
        v = interp.value(p)
        done = np.abs(v) <= tolerance * h
        active, p, v = active[~done], p[~done], v[~done]
        if active.size == 0:
            break
        g = interp.gradient(p)
        g2 = np.maximum(np.einsum("ij,ij->i", g, g), 1e-24)
        step = -(v / g2)[:, None] * g
        length = np.linalg.norm(step, axis=1, keepdims=True)
        step *= np.minimum(1.0, max_step * h / np.maximum(length, 1e-300))
        x[active] = p + step
    unconverged = int(np.count_nonzero(np.abs(interp.value(x)) > tolerance * h))
    return x, unconverged


def redistance(phi: np.ndarray, voxel: float) -> np.ndarray:
    return oracle.edt(phi < 0, voxel)["values"]


def cover_gaps(phi: np.ndarray, origin, voxel: float, interp: Interpolant, samples: np.ndarray, radius: float) -> np.ndarray:
    """New samples on the zero level set of `phi` (indexed [k, j, i]) so that every vertex of
    its marching-cubes surface has a sample within `radius` (world units): see the module doc."""
    from scipy.spatial import cKDTree

    nz, ny, nx = phi.shape
    V = oracle.marching_cubes(phi.ravel(), (nx, ny, nz), tuple(np.asarray(origin, np.float64)), voxel)["V"]
    if len(V) == 0:
        return np.zeros((0, 3))
    if len(samples):
        d, _ = cKDTree(samples).query(V, k=1, distance_upper_bound=radius * (1 + 1e-12))
        open_ = V[~(d <= radius)]
    else:
        open_ = V
    # Greedy in vertex order: a vertex is kept unless a kept one lies within the radius
    # (cells of edge `radius`: the kept ones near a vertex are in its 27 cells).
    cells: dict[tuple[int, int, int], list[tuple[float, float, float]]] = {}
    r2 = radius * radius
    kept = []
    keys = np.floor(open_ / radius).astype(np.int64).tolist()
    for (cx, cy, cz), (x, y, z) in zip(keys, open_.tolist()):
        near = any(
            (qx - x) ** 2 + (qy - y) ** 2 + (qz - z) ** 2 <= r2
            for dz in (-1, 0, 1)
            for dy in (-1, 0, 1)
            for dx in (-1, 0, 1)
            for (qx, qy, qz) in cells.get((cx + dx, cy + dy, cz + dz), ())
        )
        if not near:
            cells.setdefault((cx, cy, cz), []).append((x, y, z))
            kept.append((x, y, z))
    if not kept:
        return np.zeros((0, 3))
    x, _ = project(interp, np.asarray(kept))
    converged = np.abs(interp.value(x)) <= 1e-3 * voxel
    return x[converged]


def decompose(
    phi0: np.ndarray, origin, voxel: float, samples: np.ndarray, dt: float, steps: int, levels: int, cover: float = 0.25
) -> dict:
    """Levels 1..N: the level sets φ_0..φ_N, samples X_0..X_N, normals n_0..n_N, details W_i
    and the mean |w_i| per level. X_{i−1}, n_{i−1} and W_i include the samples added before
    level i (`cover` voxels, 0: none), so each holds more samples than the one before."""
    phi = redistance(phi0, voxel)
    interp = Interpolant(phi, origin, voxel)
    samples, _ = project(interp, samples)
    phis, xs, normals, details, mean_abs, unconverged = [phi], [samples], [unit_normals(interp, samples)], [], [], []
    x = samples
    cover_seconds = 0.0
    for _ in range(levels):
        if cover > 0:
            t0 = time.perf_counter()
            new = cover_gaps(phi, origin, voxel, interp, x, cover * voxel)
            x = np.concatenate([x, new])
            xs[-1] = x
            normals[-1] = np.concatenate([normals[-1], unit_normals(interp, new)])
            cover_seconds += time.perf_counter() - t0
        for _ in range(steps):
            phi = oracle.mbo_step(phi, voxel, dt, "vpmcf")["values"]
        interp = Interpolant(phi, origin, voxel)
        nxt, bad = project(interp, x)
        n = unit_normals(interp, nxt)
        w = nxt - x
        mean_abs.append(float(np.mean(np.abs(np.einsum("ij,ij->i", w, n)))))
        unconverged.append(bad)
        phis.append(phi)
        xs.append(nxt)
        normals.append(n)
        details.append(w)
        x = nxt
    return {
        "phis": phis,
        "samples": xs,
        "normals": normals,
        "details": details,
        "mean_abs_detail": mean_abs,
        "unconverged": unconverged,
        "cover_seconds": cover_seconds,
    }


def rebuild_from_tangent_planes(
    phi: np.ndarray,
    origin,
    voxel: float,
    previous: np.ndarray,
    normals: np.ndarray,
    details: np.ndarray,
    extension_radius: float = 1.5,
    band_margin: float = 2.0,
    k: int = 8,
    spread: float = 0.25,
    coverage: float = 0.25,
) -> np.ndarray:
    """φ_{i−1} from φ_i = `phi` and the samples of S_{i−1} (see the module doc)."""
    from scipy.spatial import cKDTree

    h = voxel
    radius = extension_radius * h
    near = band_margin * h
    moved = np.linalg.norm(details, axis=1)
    band = float(moved.max(initial=0.0)) + near
    out = phi.copy()
    nodes = np.nonzero(np.abs(phi) < band)  # (k, j, i) index arrays
    world = np.stack(nodes[::-1], axis=1) * h + np.asarray(origin, np.float64)
    tree = cKDTree(previous)
    dist, idx = tree.query(world, k=min(k, len(previous)))
    if dist.ndim == 1:
        dist, idx = dist[:, None], idx[:, None]
    # Gaussian weights of σ = radius/2, relative to the nearest sample (as vesselmsr's
    # weighted_nearest), for the reach; σ = spread·h for the planes; nodes farther than
    # band + radius from every sample keep φ_i's side.
    d2 = dist**2
    wgt = np.exp(-(d2 - d2[:, :1]) / (2.0 * (0.5 * radius) ** 2))
    wsum = np.maximum(wgt.sum(axis=1), 1e-300)
    diff = world[:, None, :] - previous[idx]
    plane = np.einsum("nkc,nkc->nk", normals[idx], diff)
    wp = np.exp(-(d2 - d2[:, :1]) / (2.0 * (spread * h) ** 2))
    value = (wp * plane).sum(axis=1) / np.maximum(wp.sum(axis=1), 1e-300)
    d_min = dist[:, 0]
    value = np.copysign(np.clip(np.abs(value), np.maximum(d_min - coverage * h, 0.0), d_min), value)
    d2w = (wgt * d2).sum(axis=1) / wsum
    m = (wgt * moved[idx]).sum(axis=1) / wsum
    use = (d2w <= (near + np.minimum(m, 2 * h)) ** 2) & (d2[:, 0] <= (band + radius) ** 2)
    cur = phi[nodes]
    clamped = np.where(np.abs(cur) < near, np.copysign(near, cur), cur)
    out[nodes] = np.where(use, value, clamped)
    return redistance(out, voxel)


def run(phi0: np.ndarray, side: dict, samples: np.ndarray, dt: float, steps: int, levels: int, cover: float = 0.25) -> dict:
    voxel = float(side["voxel"])
    origin = np.asarray(side["origin"], np.float64)
    t0 = time.perf_counter()
    d = decompose(phi0, origin, voxel, samples, dt, steps, levels, cover)
    t1 = time.perf_counter()
    rebuilt = [
        rebuild_from_tangent_planes(d["phis"][i], origin, voxel, d["samples"][i - 1], d["normals"][i - 1], d["details"][i - 1])
        for i in range(1, levels + 1)
    ]
    t2 = time.perf_counter()
    # Agreement of each rebuilt φ_{i−1} with the true one near the surface (|φ| < 2h), in h.
    agree = [
        float(np.mean(np.abs(r - t)[np.abs(t) < 2 * voxel]) / voxel) for r, t in zip(rebuilt, d["phis"][:-1])
    ]
    return {
        "seconds": t2 - t0,
        "decompose_seconds": t1 - t0,
        "cover_seconds": d["cover_seconds"],
        "rebuild_seconds": t2 - t1,
        "mean_abs_detail": d["mean_abs_detail"],
        "unconverged": d["unconverged"],
        "rebuild_mean_abs_error_h": agree,
        "samples": int(len(samples)),
        "samples_final": int(len(d["samples"][-1])),
    }


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) not in (5, 6):
        print("usage: msr.py PHI.npy POINTS.f64 DT STEPS LEVELS [COVER]", file=sys.stderr)
        return 1
    try:
        phi, side = oracle.read_npy_grid(argv[0])
        pts = oracle.read_points(argv[1])
        dt, steps, levels = float(argv[2]), int(argv[3]), int(argv[4])
        cover = float(argv[5]) if len(argv) == 6 else 0.25
        if steps < 1 or levels < 1:
            raise oracle.OracleError("STEPS and LEVELS must be at least 1")
        if not (math.isfinite(cover) and cover >= 0):
            raise oracle.OracleError(f"COVER must be a non-negative number of voxels, got {cover}")
        res = run(phi.astype(np.float64), side, pts, dt, steps, levels, cover)
    except (oracle.OracleError, ValueError) as e:
        print(f"msr: error: {e}", file=sys.stderr)
        return 1
    print(json.dumps(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
