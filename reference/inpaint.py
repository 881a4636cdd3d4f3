#!/usr/bin/env python3
"""Reference axial inpainting in numpy/scipy/libigl: the speed (and sanity) reference of
`vesselmsr::inpaint::repair::repair` with its default method `axial` (issue 6; paper Section 4,
Algorithm 4, the fill of `src/inpaint/axial.rs`).

The same loop as `repair`, up to the filled φ (no marching cubes: skimage is not a dependency):

1. voxel h: given, or the project's default rule min(mean unique edge / 2, longest extent / 256);
   the lattice of the whole mesh (origin = bbox min − pad, pad = 4h + margin + 2·r_max,
   margin = 6h, the axial fill's) and the sub-box of its nodes around the balls with that margin, as
   `src/inpaint/repair.rs` builds them. The mesh is used as read (a closed input is expected;
   `repair` caps open ends first — the winding-number sign tolerates holes anyway).
2. φ_0: libigl signed distance at the sub-box nodes (fast-winding-number sign, exact distance
   to the closest point), as reference/oracle.py `signed_distance`.
3. the axis of each ball: eigenvector of the smallest eigenvalue (numpy `eigh`) of the
   area-weighted normal covariance Σ A n nᵀ of the triangles whose centroid lies 1..2 ball
   radii from the centre (`src/inpaint/axis.rs`).
4. the axial fill: every node x inside D finds where x ± s·a leaves D (exactly: the far side of
   each ball holding the point, repeated); φ_0 there by trilinear interpolation (`scipy.ndimage.map_coordinates`, order 1),
   ψ(x) = (t₋ φ_0(x + t₊a) + t₊ φ_0(x − t₋a)) / (t₊ + t₋); one end alone when the other leaves
   the grid, φ_0 kept when both do. Vectorised over the nodes of D.
5. the union with the input, ψ ← min(ψ, φ_0), then the blend ψ ← w ψ + (1 − w) φ_0 with the
   cubic smoothstep w of the depth over 2h inside ∂D (`src/inpaint/mask.rs`).

Measured: the volume of {φ < 0} inside D (the union of the balls), of φ_0 and of the filled φ,
by trilinear φ at the points of a lattice 3× finer than the grid that lie in D (each point
stands for (h/3)³).

CLI: `python inpaint.py MESH --region x,y,z,r [--region ...] [--voxel H] [--out PHI.f64]`
prints one JSON line: seconds (signed distance + axis + fill + blend, no I/O), seconds_sdf,
seconds_axis, seconds_fill, seconds_blend, voxel, dims, origin, nodes_in_D, axes,
volume_in_D_of_phi0, volume_in_D_of_filled_phi. `--out` writes the filled φ as raw float64, x
fastest (the oracle's grid format). Errors: one line on stderr, exit 1.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy import ndimage

sys.path.insert(0, str(Path(__file__).resolve().parent))
import oracle  # noqa: E402
from oracle import OracleError  # noqa: E402

MARGIN_VOXELS = 6.0
DEFAULT_MIN_CELLS = 256
SUPERSAMPLE = 3


def mean_unique_edge(V: np.ndarray, F: np.ndarray) -> float:
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    E = np.unique(E, axis=0)
    return float(np.linalg.norm(V[E[:, 1]] - V[E[:, 0]], axis=1).mean()) if len(E) else 0.0


def default_voxel(V: np.ndarray, F: np.ndarray) -> float:
    used = V[np.unique(F)]
    longest = float((used.max(0) - used.min(0)).max())
    cap = longest / DEFAULT_MIN_CELLS
    resolve = mean_unique_edge(V, F) / 2.0
    return min(resolve, cap) if resolve > 0 else cap


def sub_box(V: np.ndarray, F: np.ndarray, balls: np.ndarray, h: float):
    """(origin of the sub-box, dims (nx, ny, nz)) on the whole mesh's lattice, as repair.rs."""
    used = V[np.unique(F)]
    lo, hi = used.min(0), used.max(0)
    rmax = float(balls[:, 3].max())
    margin = MARGIN_VOXELS * h  # the axial fill's margin in repair.rs
    pad = 4.0 * h + margin + 2.0 * rmax
    origin = lo - pad
    whole = np.ceil((hi - lo + 2.0 * pad) / h).astype(int) + 1
    first = np.full(3, np.iinfo(np.int64).max)
    last = np.zeros(3, int)
    for c in balls:
        lo_b = np.floor((c[:3] - c[3] - margin - origin) / h)
        hi_b = np.ceil((c[:3] + c[3] + margin - origin) / h)
        first = np.minimum(first, np.maximum(lo_b, 0).astype(int))
        last = np.maximum(last, np.minimum(np.maximum(hi_b, 0).astype(int), whole - 1))
    dims = np.maximum(last - first, 0) + 1
    if (dims < 4).any():
        raise OracleError("the regions lie outside the mesh's bounding box")
    return origin + first * h, dims


def estimate_axis(V: np.ndarray, F: np.ndarray, ball: np.ndarray, shell: float = 2.0):
    tri = V[F]
    cen = tri.mean(1)
    r = np.linalg.norm(cen - ball[:3], axis=1) / ball[3]
    raw = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    a2 = np.linalg.norm(raw, axis=1)
    keep = (r >= 1.0) & (r <= shell) & (a2 > 0)
    if not keep.any():
        return None
    n = raw[keep] / a2[keep, None]
    cov = (n[:, :, None] * n[:, None, :] * a2[keep, None, None]).sum(0)
    w, vec = np.linalg.eigh(cov)
    a = vec[:, int(np.argmin(w))]
    return a / np.linalg.norm(a)


def depth_of(P: np.ndarray, balls: np.ndarray):
    """Largest r − |p − c| over the balls, and the ball that gives it."""
    d = balls[None, :, 3] - np.linalg.norm(P[:, None, :] - balls[None, :, :3], axis=2)
    b = np.argmax(d, axis=1)
    return d[np.arange(len(P)), b], b


def sample(phi: np.ndarray, origin: np.ndarray, h: float, P: np.ndarray):
    """Trilinear φ at world points P (phi indexed [i, j, k]); NaN outside the node box."""
    u = (P - origin) / h
    dims = np.array(phi.shape)
    inside = ((u >= 0) & (u <= dims - 1)).all(1)
    out = np.full(len(P), np.nan)
    if inside.any():
        out[inside] = ndimage.map_coordinates(phi, u[inside].T, order=1, mode="nearest")
    return out


def fill_axial(phi0, origin, h, balls, axes):
    """The axial fill of the nodes inside D (returns a new grid)."""
    nx, ny, nz = phi0.shape
    I, J, K = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    P = origin + h * np.stack([I.ravel(), J.ravel(), K.ravel()], 1)
    d, b = depth_of(P, balls)
    inD = np.flatnonzero(d > 0)
    P, b = P[inD], b[inD]
    A = axes[b]
    ends = []
    for sign in (1.0, -1.0):
        D = sign * A
        # Where the line leaves the union of balls: jump to the far side of every ball that
        # holds the current point until none does (exact, as src/inpaint/axial.rs).
        s = np.zeros(len(P))
        for _ in range(len(balls) + 1):
            Q = P + s[:, None] * D
            far = s.copy()
            for c in balls:
                m = Q - c[:3]
                cc = (m * m).sum(1) - c[3] ** 2
                bb = (m * D).sum(1)
                inside = cc < 0
                far[inside] = np.maximum(far[inside], s[inside] - bb[inside] + np.sqrt(bb[inside] ** 2 - cc[inside]))
            moved = far > s
            if not moved.any():
                break
            s[moved] = far[moved] + 1e-6 * h
        Q = P + s[:, None] * D
        ends.append((s, sample(phi0, origin, h, Q)))
    (tp, vp), (tm, vm) = ends
    both = ~np.isnan(vp) & ~np.isnan(vm)
    value = phi0.ravel()[inD].copy()
    value[both] = (tm[both] * vp[both] + tp[both] * vm[both]) / (tp[both] + tm[both])
    only_p = ~np.isnan(vp) & np.isnan(vm)
    only_m = np.isnan(vp) & ~np.isnan(vm)
    value[only_p] = vp[only_p]
    value[only_m] = vm[only_m]
    psi = phi0.copy()
    psi.ravel()[inD] = value
    return psi, d.reshape(phi0.shape), len(inD)


def blend(psi, phi0, depth, band):
    s = np.clip(depth / band, 0.0, 1.0)
    w = s * s * (3.0 - 2.0 * s)
    return w * psi + (1.0 - w) * phi0


def volume_in_D(phi, origin, h, balls, k: int = SUPERSAMPLE) -> float:
    """Volume of {φ < 0} ∩ D by trilinear φ on a lattice k× finer than the grid, in D only."""
    step = h / k
    lo = (balls[:, :3] - balls[:, 3:]).min(0)
    hi = (balls[:, :3] + balls[:, 3:]).max(0)
    axes = [np.arange(lo[a] + 0.5 * step, hi[a], step) for a in range(3)]
    total = 0
    for z in axes[2]:  # slab by slab to bound memory
        X, Y = np.meshgrid(axes[0], axes[1], indexing="ij")
        P = np.stack([X.ravel(), Y.ravel(), np.full(X.size, z)], 1)
        P = P[depth_of(P, balls)[0] > 0]
        if len(P):
            v = sample(phi, origin, h, P)
            total += int(np.count_nonzero(v < 0))
    return total * step**3


def inpaint(V, F, balls, voxel=None):
    """The reference loop (module docs); returns (result dict, filled φ indexed [i, j, k])."""
    balls = np.asarray(balls, np.float64).reshape(-1, 4)
    if len(F) == 0:
        raise OracleError("mesh has no triangles")
    if len(balls) == 0 or not (balls[:, 3] > 0).all() or not np.isfinite(balls).all():
        raise OracleError("regions need finite centres and radii > 0")
    h = float(voxel) if voxel is not None else default_voxel(V, F)
    if not (h > 0 and np.isfinite(h)):
        raise OracleError(f"voxel must be positive, got {h}")
    origin, dims = sub_box(V, F, balls, h)
    nx, ny, nz = (int(n) for n in dims)
    I, J, K = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    nodes = origin + h * np.stack([I.ravel(), J.ravel(), K.ravel()], 1)
    t0 = time.perf_counter()
    phi0 = oracle.signed_distance(V, F, nodes)["values"].reshape(nx, ny, nz)
    t1 = time.perf_counter()
    axes = []
    for c in balls:
        a = estimate_axis(V, F, c)
        if a is None:
            raise OracleError(f"no surface around the region at {c[:3]} to take the axis from")
        axes.append(a)
    axes = np.array(axes)
    t2 = time.perf_counter()
    psi, depth, in_d = fill_axial(phi0, origin, h, balls, axes)
    t3 = time.perf_counter()
    psi = blend(np.minimum(psi, phi0), phi0, depth, 2.0 * h)
    t4 = time.perf_counter()
    res = {
        "seconds": t4 - t0,
        "seconds_sdf": t1 - t0,
        "seconds_axis": t2 - t1,
        "seconds_fill": t3 - t2,
        "seconds_blend": t4 - t3,
        "voxel": h,
        "dims": [nx, ny, nz],
        "origin": origin.tolist(),
        "nodes_in_D": in_d,
        "axes": axes.tolist(),
        "volume_in_D_of_phi0": volume_in_D(phi0, origin, h, balls),
        "volume_in_D_of_filled_phi": volume_in_D(psi, origin, h, balls),
    }
    return res, psi


def _ball(text: str):
    try:
        v = [float(x) for x in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"region '{text}': expected x,y,z,r") from None
    if len(v) != 4 or not np.isfinite(v).all() or v[3] <= 0:
        raise argparse.ArgumentTypeError(f"region '{text}': expected x,y,z,r with r > 0")
    return v


def main(argv: list[str] | None = None) -> int:
    p = oracle._Parser(prog="inpaint.py", description=__doc__.split("\n\n")[0])
    p.add_argument("mesh")
    p.add_argument("--region", type=_ball, action="append", required=True, help="x,y,z,r")
    p.add_argument("--voxel", type=float, default=None, help="voxel h, world units")
    p.add_argument("--out", default=None, help="filled φ as raw float64, x fastest")
    args = p.parse_args(argv)
    try:
        with oracle._stdout_to_stderr():
            V, F = oracle.load_mesh(args.mesh)
            res, psi = inpaint(V, F, args.region, args.voxel)
            if args.out:
                np.ascontiguousarray(psi.transpose(2, 1, 0), np.float64).tofile(args.out)
    except OracleError as e:
        print(f"inpaint: error: {e}", file=sys.stderr)
        return 1
    except Exception as e:  # library failures: still one line on stderr and exit 1
        print(f"inpaint: error: {type(e).__name__}: {e}", file=sys.stderr)
        return 1
    print(json.dumps(oracle._jsonable(res)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
