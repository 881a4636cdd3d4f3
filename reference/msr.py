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
* each φ_{i−1} is then rebuilt from φ_i and (X_{i−1}, n_{i−1}, W_i): near the samples a node
  takes the Gaussian-weighted (σ = h/4, relative to the nearest) mean over its 8 nearest samples
  (`scipy.spatial.cKDTree`) of its signed distance to their tangent planes, its magnitude kept
  within [d_min − `coverage`, d_min] (d_min: the nearest sample's distance); elsewhere the side
  of φ_i (at least `band_margin` voxels from the surface); then distance_transform_edt.
  (vesselmsr also adds samples where a level's surface has none within h/4, from its
  marching-cubes surface; this reference does not, which only makes it cheaper.)

CLI: `python msr.py PHI.npy POINTS.f64 DT STEPS LEVELS` prints one JSON line with "seconds"
(decompose + rebuilds, no I/O), "decompose_seconds", "rebuild_seconds", "mean_abs_detail"
(per level, world units), "samples", "unconverged" (per level).
"""

from __future__ import annotations

import json
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


def decompose(phi0: np.ndarray, origin, voxel: float, samples: np.ndarray, dt: float, steps: int, levels: int) -> dict:
    """Levels 1..N: the level sets φ_0..φ_N, samples X_0..X_N, normals n_0..n_N, details W_i
    and the mean |w_i| per level."""
    phi = redistance(phi0, voxel)
    interp = Interpolant(phi, origin, voxel)
    samples, _ = project(interp, samples)
    phis, xs, normals, details, mean_abs, unconverged = [phi], [samples], [unit_normals(interp, samples)], [], [], []
    x = samples
    for _ in range(levels):
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


def run(phi0: np.ndarray, side: dict, samples: np.ndarray, dt: float, steps: int, levels: int) -> dict:
    voxel = float(side["voxel"])
    origin = np.asarray(side["origin"], np.float64)
    t0 = time.perf_counter()
    d = decompose(phi0, origin, voxel, samples, dt, steps, levels)
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
        "rebuild_seconds": t2 - t1,
        "mean_abs_detail": d["mean_abs_detail"],
        "unconverged": d["unconverged"],
        "rebuild_mean_abs_error_h": agree,
        "samples": int(len(samples)),
    }


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 5:
        print("usage: msr.py PHI.npy POINTS.f64 DT STEPS LEVELS", file=sys.stderr)
        return 1
    try:
        phi, side = oracle.read_npy_grid(argv[0])
        pts = oracle.read_points(argv[1])
        dt, steps, levels = float(argv[2]), int(argv[3]), int(argv[4])
        if steps < 1 or levels < 1:
            raise oracle.OracleError("STEPS and LEVELS must be at least 1")
        res = run(phi.astype(np.float64), side, pts, dt, steps, levels)
    except (oracle.OracleError, ValueError) as e:
        print(f"msr: error: {e}", file=sys.stderr)
        return 1
    print(json.dumps(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
