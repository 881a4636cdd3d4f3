#!/usr/bin/env python3
"""Reference vessel centerlines by kimimaro's TEASAR skeleton and trimesh plane sections: the
independent route that `vesselmsr centerline` (issue 20) is checked and raced against.

Nothing here comes from the Rust code; only the voxel rule and the JSON shape are shared.

1. voxel h: given (`--voxel`), or the project's default rule
   min(mean unique edge / 2, longest bounding-box extent / 256).
2. inside mask: libigl's winding number |w| > 0.5 at the nodes of a lattice of spacing h
   covering the bounding box with PAD_VOXELS nodes to spare on every side (node (i, j, k) at
   origin + h·(i, j, k)); `fast_winding_number`, or the exact `winding_number` for meshes of at
   most EXACT_WINDING_MAX_FACES triangles (the fast one crawls on the sliver triangles of small
   analytic meshes). The generalized winding number closes open vessel ends (near the plane of
   the hole) and does not care about the orientation (the capped aorta is inward).
3. skeleton: `kimimaro.skeletonize` of the mask (anisotropy h on every axis, so its vertices and
   distances are in world units; TEASAR rolling-ball invalidation radius SCALE·DBF +
   CONST_VOXELS·h, kimimaro's default penalty field, soma handling off, components below
   DUST_VOXELS voxels dropped). kimimaro's distance-to-boundary (DBF) at each vertex is kept
   per point as "radius_dbf".
4. open ends: the mesh's boundary loops (edges with one triangle), each with its centroid c and
   equivalent radius ρ = perimeter / 2π. TEASAR traces a bush of paths to the rim of each flat,
   winding-number-closed opening: the skeleton vertices within ρ + OPEN_END_SLACK_VOXELS·h of c
   are removed, components shorter than twice their largest DBF dropped, and c is joined
   straight (a vertex every h) to the nearest vertex left whose DBF is at least CORE_FRACTION·ρ:
   an open end.
5. graph from the skeleton's edges: endpoints (degree 1), junctions (degree >= 3; adjacent
   junction vertices form one junction at their mean position), branches = vertex chains between
   them; closed chains without endpoint or junction are one branch. Spurs are pruned: branches
   from a junction to an endpoint (not an open end) shorter than SPUR_FACTOR × the junction's
   DBF are removed, all at once, and the graph rebuilt, until none is left.
6. each branch: smoothed (SMOOTH_ITERATIONS passes of p_i <- (p_{i-1} + 2 p_i + p_{i+1}) / 4, its
   two ends fixed) to take the voxel staircase out; then RECENTRE_PASSES passes move each inner
   point to the area centroid of its section loop (item 8) when that loop is one lumen (its
   equivalent radius RECENTRE_LUMEN times the DBF: a section across a junction takes in the other
   branches) and the move is at most RECENTRE_MAX_FRACTION·DBF + h; a closed end that is no open end is finished by `_finish_blunt_end` (cut where
   the rest lies within 1.5 DBF, continued straight along the tangent to the wall); tangent at a point = the chord between the points TANGENT_HALF_WINDOW_VOXELS·h of
   arc length before and after it (clamped to the branch); length = the polyline's length.
7. radius at each point (and junction) = its exact distance to the mesh surface
   (`igl.point_mesh_squared_distance`): the maximal inscribed radius for a point on the axis.
   (kimimaro's DBF is the distance from a node to the nearest outside node: off by up to a voxel,
   and more where the voxel path strays from the axis.)
8. equivalent diameter at each point: `trimesh.Trimesh.section` by the plane through the point
   perpendicular to its tangent; of the closed loops of the section (projected to the plane), the
   smallest one holding the point, else the one with the vertex nearest it: d = 2·sqrt(A/π), A its
   shoelace area; null when the section has no closed loop.

CLI:
  `python centerline.py MESH -o OUT.json [--voxel H]` writes the centerline JSON (the shape of
  `vesselmsr centerline -o CL.json`, plus "equivalent_diameter" per branch point) and prints one
  JSON line with the counts and timings;
  `python centerline.py --compare OURS.json REF.json` prints one JSON line of comparison figures
  (see `compare`). Errors: one line on stderr, exit 1.

From Python: `centerline(V, F, voxel=None)` returns the JSON dict; `compare(ours, ref)` the
figures.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import oracle  # noqa: E402
from oracle import OracleError  # noqa: E402
from inpaint import default_voxel  # noqa: E402  (the project's voxel rule, as inpaint.py has it)

PAD_VOXELS = 3
SCALE = 1.5
CONST_VOXELS = 2.0
DUST_VOXELS = 64
SMOOTH_ITERATIONS = 8
TANGENT_HALF_WINDOW_VOXELS = 2.0
OPEN_END_SLACK_VOXELS = 2.0
SPUR_FACTOR = 1.0
CORE_FRACTION = 0.25
RECENTRE_PASSES = 2
RECENTRE_MAX_FRACTION = 0.1
RECENTRE_LUMEN = (0.75, 1.3)
EXACT_WINDING_MAX_FACES = 2000
BLUNT_END_REACH = 1.5


# ---------------------------------------------------------------------------------------------
# voxel rule and mask


def _winding(V: np.ndarray, F: np.ndarray, Q: np.ndarray) -> np.ndarray:
    import igl

    if len(F) <= EXACT_WINDING_MAX_FACES:
        return igl.winding_number(V, F, Q)  # exact: fast_winding_number crawls on slivers
    return igl.fast_winding_number(V, F, Q)


def inside_mask(V: np.ndarray, F: np.ndarray, h: float):
    """(mask uint8 of shape (nx, ny, nz), origin): |winding number| > 0.5 at the nodes."""
    import igl

    used = V[np.unique(F)]
    lo, hi = used.min(0), used.max(0)
    origin = lo - PAD_VOXELS * h
    dims = np.ceil((hi - lo) / h).astype(int) + 1 + 2 * PAD_VOXELS
    axes = [origin[a] + h * np.arange(dims[a]) for a in range(3)]
    X, Y, Z = np.meshgrid(*axes, indexing="ij")
    Q = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
    w = _winding(V, F, Q)
    mask = (np.abs(w) > 0.5).reshape(tuple(dims)).astype(np.uint8)
    return mask, origin


# ---------------------------------------------------------------------------------------------
# boundary loops (open vessel ends)


def boundary_loops(F: np.ndarray, V: np.ndarray) -> list[dict]:
    """Centroid and equivalent radius (perimeter / 2π) of each loop of one-triangle edges."""
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    uniq, counts = np.unique(E, axis=0, return_counts=True)
    b = uniq[counts == 1]
    if len(b) == 0:
        return []
    parent = {}

    def find(x):
        while parent.setdefault(x, x) != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for a, c in b:
        ra, rc = find(int(a)), find(int(c))
        if ra != rc:
            parent[ra] = rc
    groups: dict[int, list[int]] = {}
    for i, (a, _) in enumerate(b):
        groups.setdefault(find(int(a)), []).append(i)
    loops = []
    for idx in groups.values():
        edges = b[idx]
        mids = 0.5 * (V[edges[:, 0]] + V[edges[:, 1]])
        lens = np.linalg.norm(V[edges[:, 1]] - V[edges[:, 0]], axis=1)
        perimeter = float(lens.sum())
        centroid = (mids * lens[:, None]).sum(0) / max(perimeter, 1e-300)
        loops.append({"centroid": centroid, "radius": perimeter / (2 * math.pi)})
    return loops


# ---------------------------------------------------------------------------------------------
# skeleton graph


def _skeleton(mask: np.ndarray, h: float):
    import kimimaro

    params = {
        "scale": SCALE,
        "const": CONST_VOXELS * h,
        "pdrf_scale": 100000,
        "pdrf_exponent": 4,
        "soma_acceptance_threshold": 1e30,
        "soma_detection_threshold": 1e30,
        "soma_invalidation_const": 0.0,
        "soma_invalidation_scale": 1.0,
    }
    skels = kimimaro.skeletonize(
        np.asfortranarray(mask),
        teasar_params=params,
        anisotropy=(h, h, h),
        dust_threshold=DUST_VOXELS,
        progress=False,
        fix_branching=True,
        fix_borders=True,
        parallel=1,
    )
    verts, edges, radii = [], [], []
    n = 0
    for sk in skels.values():
        verts.append(np.asarray(sk.vertices, np.float64))
        edges.append(np.asarray(sk.edges, np.int64) + n)
        radii.append(np.asarray(sk.radius, np.float64))
        n += len(sk.vertices)
    if n == 0:
        return np.zeros((0, 3)), np.zeros((0, 2), np.int64), np.zeros(0)
    return np.concatenate(verts), np.concatenate(edges), np.concatenate(radii)


def _polyline_length(P: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum()) if len(P) > 1 else 0.0


def _graph(P: np.ndarray, edges: np.ndarray):
    """Branches (vertex chains) between nodes; junction clusters; per-vertex degree."""
    n = len(P)
    e = np.sort(edges, axis=1)
    e = e[e[:, 0] != e[:, 1]]
    e = np.unique(e, axis=0) if len(e) else e
    adj: list[list[int]] = [[] for _ in range(n)]
    for a, b in e:
        adj[a].append(int(b))
        adj[b].append(int(a))
    deg = np.array([len(x) for x in adj])
    # junction clusters: union of adjacent degree >= 3 vertices
    cluster = -np.ones(n, np.int64)
    clusters: list[list[int]] = []
    for v in range(n):
        if deg[v] >= 3 and cluster[v] < 0:
            cid = len(clusters)
            stack, members = [v], []
            cluster[v] = cid
            while stack:
                u = stack.pop()
                members.append(u)
                for w in adj[u]:
                    if deg[w] >= 3 and cluster[w] < 0:
                        cluster[w] = cid
                        stack.append(w)
            clusters.append(members)
    is_node = (deg != 2) & (deg > 0)
    seen = set()
    chains = []
    for v in range(n):
        if not is_node[v]:
            continue
        for w in adj[v]:
            if (min(v, w), max(v, w)) in seen:
                continue
            if cluster[v] >= 0 and cluster[v] == cluster[w]:
                seen.add((min(v, w), max(v, w)))
                continue
            chain = [v, w]
            seen.add((min(v, w), max(v, w)))
            prev, cur = v, w
            while not is_node[cur]:
                nxt = adj[cur][0] if adj[cur][0] != prev else adj[cur][1]
                seen.add((min(cur, nxt), max(cur, nxt)))
                prev, cur = cur, nxt
                chain.append(cur)
            chains.append(chain)
    # closed chains (every vertex of degree 2)
    for v in range(n):
        if deg[v] == 2 and not any((min(v, w), max(v, w)) in seen for w in adj[v]):
            chain = [v]
            prev, cur = v, adj[v][0]
            seen.add((min(v, cur), max(v, cur)))
            while cur != v:
                chain.append(cur)
                nxt = adj[cur][0] if adj[cur][0] != prev else adj[cur][1]
                seen.add((min(cur, nxt), max(cur, nxt)))
                prev, cur = cur, nxt
            chain.append(v)
            chains.append(chain)
    return chains, clusters, cluster, deg, e


def _components(n: int, edges: np.ndarray):
    """Component id per vertex over `edges` (-1 for vertices on no edge), and the count."""
    comp = -np.ones(n, np.int64)
    adj: dict[int, list[int]] = {}
    for a, b in edges:
        adj.setdefault(int(a), []).append(int(b))
        adj.setdefault(int(b), []).append(int(a))
    count = 0
    for v in adj:
        if comp[v] >= 0:
            continue
        stack = [v]
        comp[v] = count
        while stack:
            u = stack.pop()
            for w in adj[u]:
                if comp[w] < 0:
                    comp[w] = count
                    stack.append(w)
        count += 1
    return comp, count


def _prune_spurs(P, R, edges, protected: set):
    """Removes junction-to-endpoint branches shorter than SPUR_FACTOR × the junction's radius
    whose endpoint is not `protected`, all such at once, until none is left. Returns the kept
    edges."""
    while True:
        chains, clusters, cluster, deg, e = _graph(P, edges)
        drop = set()
        for ch in chains:
            a, b = ch[0], ch[-1]
            for end, other in ((a, b), (b, a)):
                if deg[end] == 1 and cluster[other] >= 0:
                    jr = max(R[u] for u in clusters[cluster[other]])
                    if end not in protected and _polyline_length(P[ch]) < SPUR_FACTOR * jr:
                        # drop the chain's edges (its junction vertex stays)
                        drop.update((min(x, y), max(x, y)) for x, y in zip(ch, ch[1:]))
                    break
        if not drop:
            return e
        edges = np.array([ed for ed in map(tuple, e) if ed not in drop], np.int64).reshape(-1, 2)


def _drop_small_components(P, R, edges, open_ends: set):
    """Edges of the components that hold an open end or are at least twice as long as their
    largest radius."""
    comp, count = _components(len(P), edges)
    if count == 0:
        return edges
    length = np.zeros(count)
    np.add.at(length, comp[edges[:, 0]], np.linalg.norm(P[edges[:, 1]] - P[edges[:, 0]], axis=1))
    rmax = np.zeros(count)
    np.maximum.at(rmax, comp[comp >= 0], R[comp >= 0])
    good = length >= 2.0 * rmax
    for v in open_ends:
        if comp[v] >= 0:
            good[comp[v]] = True
    return edges[good[comp[edges[:, 0]]]]


def _clean(P, R, edges, loops, h):
    """The skeleton made a vessel centerline. At each open end (boundary loop of centroid c and
    equivalent radius ρ) the vertices within ρ + OPEN_END_SLACK_VOXELS·h of c are removed (the
    bush of paths TEASAR traces to the rim of the flat, winding-number-closed opening), components
    shorter than twice their largest radius dropped, and c is joined straight to the nearest
    vertex left whose radius is at least CORE_FRACTION·ρ (else the nearest) by new vertices
    every h with that vertex's radius, the last at c (an open end); then spurs are pruned (`_prune_spurs`, open ends
    kept) and small components without an open end dropped again. Returns
    (P, R, edges, open-end vertices)."""
    keep = np.ones(len(P), bool)
    for lp in loops:
        keep &= np.linalg.norm(P - lp["centroid"], axis=1) > lp["radius"] + OPEN_END_SLACK_VOXELS * h
    edges = _drop_small_components(P, R, edges[keep[edges[:, 0]] & keep[edges[:, 1]]], set())
    kept = np.unique(edges)
    P, R, edges = list(P), list(R), [tuple(map(int, e)) for e in edges]
    open_ends = set()
    for lp in loops:
        if len(kept) == 0:
            break
        # the nearest vertex on the vessel's core (not a leftover of the rim bush), else any
        core = kept[np.asarray(R)[kept] >= CORE_FRACTION * lp["radius"]]
        cand = core if len(core) else kept
        d = np.linalg.norm(np.asarray(P)[cand] - lp["centroid"], axis=1)
        u = int(cand[int(np.argmin(d))])
        # the chord from u to c, a vertex every h (so smoothing and recentring can bend it)
        n = max(1, int(math.ceil(float(d.min()) / h)))
        prev = u
        for k in range(1, n + 1):
            v = len(P)
            P.append(P[u] + (k / n) * (np.asarray(lp["centroid"], np.float64) - P[u]))
            R.append(R[u])
            edges.append((prev, v))
            prev = v
        open_ends.add(prev)
    P, R = np.asarray(P).reshape(-1, 3), np.asarray(R)
    edges = np.asarray(edges, np.int64).reshape(-1, 2)
    edges = _prune_spurs(P, R, edges, open_ends)
    edges = _drop_small_components(P, R, edges, open_ends)
    return P, R, edges, open_ends


def _smooth(Q: np.ndarray, iterations: int) -> np.ndarray:
    Q = Q.copy()
    if len(Q) < 3:
        return Q
    for _ in range(iterations):
        Q[1:-1] = 0.25 * Q[:-2] + 0.5 * Q[1:-1] + 0.25 * Q[2:]
    return Q


def _tangents(Q: np.ndarray, half_window: float) -> np.ndarray:
    if len(Q) < 2:
        return np.tile([1.0, 0.0, 0.0], (len(Q), 1))
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(Q, axis=0), axis=1))])
    lo = np.clip(s - half_window, 0, s[-1])
    hi = np.clip(s + half_window, 0, s[-1])
    A = np.stack([np.interp(lo, s, Q[:, a]) for a in range(3)], axis=1)
    B = np.stack([np.interp(hi, s, Q[:, a]) for a in range(3)], axis=1)
    T = B - A
    nrm = np.linalg.norm(T, axis=1, keepdims=True)
    return T / np.where(nrm > 0, nrm, 1.0)


# ---------------------------------------------------------------------------------------------
# sections


def _plane_basis(n: np.ndarray):
    a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(n, a)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(n, e1)


def _inside_polygon(pt: np.ndarray, poly: np.ndarray) -> bool:
    x, y = pt
    xs, ys = poly[:, 0], poly[:, 1]
    xn, yn = np.roll(xs, -1), np.roll(ys, -1)
    crosses = (ys > y) != (yn > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xint = xs + (y - ys) * (xn - xs) / (yn - ys)
    return bool(np.count_nonzero(crosses & (x < xint)) % 2)


def section_loop(mesh, p: np.ndarray, t: np.ndarray):
    """(area, centroid) of the closed loop of the section of `mesh` (a trimesh.Trimesh) by the
    plane through p of normal t that holds p (the smallest such), else of the loop with the
    vertex nearest p; None when the section has no closed loop."""
    t = t / np.linalg.norm(t)
    try:
        path = mesh.section(plane_origin=p, plane_normal=t)
    except Exception:
        return None
    if path is None:
        return None
    e1, e2 = _plane_basis(t)
    best_in, best_near = None, None
    for loop in path.discrete:
        if len(loop) < 4 or not np.allclose(loop[0], loop[-1]):
            continue
        q = np.stack([(loop - p) @ e1, (loop - p) @ e2], axis=1)
        x0, y0, x1, y1 = q[:-1, 0], q[:-1, 1], q[1:, 0], q[1:, 1]
        cross = x0 * y1 - x1 * y0
        signed = 0.5 * cross.sum()
        if signed == 0:
            continue
        cx = ((x0 + x1) * cross).sum() / (6 * signed)
        cy = ((y0 + y1) * cross).sum() / (6 * signed)
        found = (abs(signed), p + cx * e1 + cy * e2)
        if _inside_polygon(np.zeros(2), q[:-1]):
            if best_in is None or found[0] < best_in[0]:
                best_in = found
        else:
            d = float(np.min(np.linalg.norm(q, axis=1)))
            if best_near is None or d < best_near[0]:
                best_near = (d, found)
    return best_in if best_in is not None else (best_near[1] if best_near else None)


def equivalent_diameter(mesh, p: np.ndarray, t: np.ndarray) -> float | None:
    """2·sqrt(A/π) of the section loop of `section_loop`; None without a closed loop."""
    found = section_loop(mesh, p, t)
    return None if found is None else 2.0 * math.sqrt(found[0] / math.pi)


def _finish_blunt_end(V, F, Q: np.ndarray, r: np.ndarray, h: float):
    """A closed (not open) end: TEASAR's last steps run from the axis to the farthest corner of
    the blunt end. The branch is cut at its first point p_i (from the inner side) that has the
    whole rest of the branch within BLUNT_END_REACH·r_i (r the DBF), and continued straight
    (every h) along the chord from the point TANGENT_HALF_WINDOW_VOXELS·h + r_i of arc before
    p_i to p_i, up to the wall: the |winding number| = 1/2 crossing along that ray (sampled every
    h/8, linear between samples). Q ends at the end; returns (Q, r)."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(Q, axis=0), axis=1))])
    left = s[-1] - s
    i = None
    for j in np.flatnonzero(left <= 3 * r.max()):
        if j >= 1 and np.linalg.norm(Q[j + 1 :] - Q[j], axis=1).max(initial=0) <= BLUNT_END_REACH * r[j]:
            i = int(j)
            break
    if i is None:
        return Q, r
    back = s[i] - (TANGENT_HALF_WINDOW_VOXELS * h + r[i])
    if back < 0:
        return Q, r
    start = np.array([np.interp(back, s, Q[:, a]) for a in range(3)])
    u = Q[i] - start
    u /= np.linalg.norm(u)
    reach = left[i] + 2 * r[i] + 2 * h
    t = np.arange(0.0, reach + h / 8, h / 8)
    w = np.abs(_winding(V, F, Q[i] + t[:, None] * u))
    out = np.flatnonzero(w < 0.5)
    if len(out) == 0 or out[0] == 0:
        return Q, r
    k = int(out[0])
    a, b = w[k - 1] - 0.5, w[k] - 0.5
    tw = t[k - 1] + (t[k] - t[k - 1]) * a / (a - b)
    n = max(1, int(math.ceil(tw / h)))
    ext = Q[i] + (np.arange(1, n + 1) / n * tw)[:, None] * u
    return np.vstack([Q[: i + 1], ext]), np.concatenate([r[: i + 1], np.full(n, r[i])])


def _recentre(mesh, Q: np.ndarray, r: np.ndarray, h: float) -> np.ndarray:
    """RECENTRE_PASSES passes: each inner point moves to the area centroid of its section loop
    (plane perpendicular to the branch's tangent there) when that loop is one lumen around the
    point (its equivalent radius within RECENTRE_LUMEN times the DBF r: a section across a
    junction takes in the other branches) and the move is at most RECENTRE_MAX_FRACTION·r + h."""
    Q = Q.copy()
    for _ in range(RECENTRE_PASSES):
        T = _tangents(Q, TANGENT_HALF_WINDOW_VOXELS * h)
        for i in range(1, len(Q) - 1):
            found = section_loop(mesh, Q[i], T[i])
            if found is None:
                continue
            eq_radius = math.sqrt(found[0] / math.pi)
            one_lumen = RECENTRE_LUMEN[0] * r[i] <= eq_radius <= RECENTRE_LUMEN[1] * r[i]
            if one_lumen and np.linalg.norm(found[1] - Q[i]) <= RECENTRE_MAX_FRACTION * r[i] + h:
                Q[i] = found[1]
    return Q


# ---------------------------------------------------------------------------------------------
# the route


def centerline(V: np.ndarray, F: np.ndarray, voxel: float | None = None, mesh_name: str = "") -> dict:
    """The reference centerline of the mesh (V, F): the JSON dict (see the module docs)."""
    import trimesh

    if len(F) == 0:
        raise OracleError(f"{mesh_name or 'mesh'}: no triangles")
    timings = {}
    t0 = time.perf_counter()
    h = float(voxel) if voxel else default_voxel(V, F)
    if not (h > 0 and math.isfinite(h)):
        raise OracleError(f"voxel must be a positive length, got {h}")
    mask, origin = inside_mask(V, F, h)
    timings["voxelize"] = time.perf_counter() - t0

    t = time.perf_counter()
    Pk, edges, R = _skeleton(mask, h)
    P = Pk + origin
    timings["skeleton"] = time.perf_counter() - t

    t = time.perf_counter()
    loops = boundary_loops(F, V)
    if len(P):
        P, R, edges, open_end_vertices = _clean(P, R, edges, loops, h)
    else:
        open_end_vertices = set()
    chains, clusters, cluster, deg, e = _graph(P, edges)
    comp, ncomp = _components(len(P), e)
    jpos = [P[m].mean(0) for m in clusters]
    # junction ids only for clusters that some branch reaches
    used_clusters = sorted({int(cluster[v]) for ch in chains for v in (ch[0], ch[-1]) if cluster[v] >= 0})
    jid = {c: i for i, c in enumerate(used_clusters)}
    branches = []
    junction_branches: dict[int, list[int]] = {i: [] for i in range(len(used_clusters))}
    for bid, ch in enumerate(chains):
        Q = P[ch].copy()
        kinds = []
        for k, v in ((0, ch[0]), (-1, ch[-1])):
            if cluster[v] >= 0:
                Q[k] = jpos[cluster[v]]
                kinds.append("junction")
                junction_branches[jid[int(cluster[v])]].append(bid)
            elif deg[v] == 1:
                kinds.append("open_end" if v in open_end_vertices else "end")
            else:
                kinds.append("end")  # closed chain
        branches.append(
            {
                "id": bid,
                "component": int(comp[ch[0]]),
                "points": _smooth(Q, SMOOTH_ITERATIONS),
                "radius_dbf": R[ch].copy(),
                "start": kinds[0],
                "end": kinds[1],
                "_ends": (ch[0], ch[-1]),
            }
        )
    timings["graph"] = time.perf_counter() - t

    t = time.perf_counter()
    mesh = trimesh.Trimesh(V, F, process=False)
    for b in branches:
        b["points"] = _recentre(mesh, b["points"], b["radius_dbf"], h)
        for first, kind, v in ((True, b["start"], b["_ends"][0]), (False, b["end"], b["_ends"][1])):
            if kind == "end" and deg[v] == 1:
                Q, r = b["points"], b["radius_dbf"]
                if first:
                    Q, r = Q[::-1], r[::-1]
                Q, r = _finish_blunt_end(V, F, Q, r, h)
                b["points"], b["radius_dbf"] = (Q[::-1], r[::-1]) if first else (Q, r)
        b["tangent"] = _tangents(b["points"], TANGENT_HALF_WINDOW_VOXELS * h)
        b["equivalent_diameter"] = [
            equivalent_diameter(mesh, p, tg) for p, tg in zip(b["points"], b["tangent"])
        ]
        b["length"] = _polyline_length(b["points"])
    timings["sections"] = time.perf_counter() - t

    t = time.perf_counter()
    import igl

    allp = [b["points"] for b in branches] + [np.asarray(jpos).reshape(-1, 3)]
    sqr, _, _ = igl.point_mesh_squared_distance(np.concatenate(allp), V, F)
    dist = np.sqrt(sqr)
    k = 0
    for b in branches:
        b["radius"] = dist[k : k + len(b["points"])]
        k += len(b["points"])
    jrad = dist[k:]
    timings["radius"] = time.perf_counter() - t
    timings["total"] = time.perf_counter() - t0

    endpoints = []
    for b in branches:
        for k, v, kind in ((0, b["_ends"][0], b["start"]), (-1, b["_ends"][1], b["end"])):
            if deg[v] == 1:
                endpoints.append(
                    {
                        "position": b["points"][k].tolist(),
                        "radius": float(b["radius"][k]),
                        "branch": b["id"],
                        "open_end": kind == "open_end",
                    }
                )
        del b["_ends"]
    junctions = [
        {
            "id": jid[c],
            "component": int(comp[clusters[c][0]]),
            "position": jpos[c].tolist(),
            "radius": float(jrad[c]),
            "branches": junction_branches[jid[c]],
        }
        for c in used_clusters
    ]
    for b in branches:
        for key in ("points", "radius", "radius_dbf", "tangent"):
            b[key] = np.asarray(b[key]).tolist()
    return {
        "mesh": mesh_name,
        "voxel": h,
        "units_note": "lengths, positions and radii in the mesh's own units; voxel h likewise",
        "route": "reference/centerline.py: libigl winding-number mask, kimimaro TEASAR skeleton, "
        "trimesh sections",
        "grid": {"dims": list(map(int, mask.shape)), "origin": origin.tolist(),
                 "inside_nodes": int(mask.sum())},
        "branches": branches,
        "junctions": junctions,
        "endpoints": endpoints,
        "components": int(ncomp),
        "timings": timings,
    }


# ---------------------------------------------------------------------------------------------
# comparison


def _resample(doc: dict, step: float):
    """Dense points (and their radii) along every branch polyline, spacing <= step."""
    pts, rad = [], []
    for b in doc["branches"]:
        P = np.asarray(b["points"], np.float64).reshape(-1, 3)
        r = np.asarray(b.get("radius", [np.nan] * len(P)), np.float64)
        if len(P) == 1:
            pts.append(P)
            rad.append(r)
            continue
        for i in range(len(P) - 1):
            seg = np.linalg.norm(P[i + 1] - P[i])
            k = max(1, int(math.ceil(seg / step)))
            s = np.arange(k)[:, None] / k
            pts.append(P[i] + s * (P[i + 1] - P[i]))
            rad.append(r[i] + s[:, 0] * (r[i + 1] - r[i]))
        pts.append(P[-1:])
        rad.append(r[-1:])
    if not pts:
        return np.zeros((0, 3)), np.zeros(0)
    return np.concatenate(pts), np.concatenate(rad)


def compare(ours: dict, ref: dict, voxel: float | None = None) -> dict:
    """Figures of two centerline JSON documents (ours and the reference): counts of branches,
    junctions, endpoints (and open ends), components, total lengths; the symmetric Hausdorff
    distance and the mean distances (each way, and their average) between the two sets of
    branch polylines resampled every h/4, and the mean |radius difference| (each of our
    resampled points against the nearest reference one); distances in units of h = `voxel`,
    else our document's voxel."""
    from scipy.spatial import cKDTree

    h = float(voxel or ours.get("voxel") or ref["voxel"])
    A, rA = _resample(ours, h / 4)
    B, rB = _resample(ref, h / 4)
    out = {"voxel": h, "voxel_ours": ours.get("voxel"), "voxel_ref": ref.get("voxel")}
    for name, doc in (("ours", ours), ("ref", ref)):
        out[f"branches_{name}"] = len(doc["branches"])
        out[f"junctions_{name}"] = len(doc["junctions"])
        out[f"endpoints_{name}"] = len(doc["endpoints"])
        out[f"open_ends_{name}"] = sum(1 for e in doc["endpoints"] if e.get("open_end"))
        out[f"components_{name}"] = doc.get("components")
        out[f"length_{name}"] = float(sum(b["length"] for b in doc["branches"]))
    if len(A) and len(B):
        dAB, iAB = cKDTree(B).query(A)
        dBA, _ = cKDTree(A).query(B)
        out["hausdorff_h"] = float(max(dAB.max(), dBA.max()) / h)
        out["hausdorff_ours_to_ref_h"] = float(dAB.max() / h)
        out["hausdorff_ref_to_ours_h"] = float(dBA.max() / h)
        out["mean_ours_to_ref_h"] = float(dAB.mean() / h)
        out["mean_ref_to_ours_h"] = float(dBA.mean() / h)
        out["mean_h"] = 0.5 * (out["mean_ours_to_ref_h"] + out["mean_ref_to_ours_h"])
        dr = np.abs(rA - rB[iAB])
        out["mean_abs_radius_diff_h"] = float(np.nanmean(dr) / h) if np.isfinite(dr).any() else None
    else:
        out["hausdorff_h"] = out["mean_h"] = out["mean_abs_radius_diff_h"] = None
    return out


# ---------------------------------------------------------------------------------------------
# CLI


def main(argv: list[str] | None = None) -> int:
    p = oracle._Parser(prog="centerline.py", description=__doc__.split("\n\n")[0])
    p.add_argument("mesh", nargs="?")
    p.add_argument("-o", "--out", default=None, help="centerline JSON to write")
    p.add_argument("--voxel", type=float, default=None, help="voxel h, world units")
    p.add_argument("--compare", nargs=2, metavar=("OURS", "REF"), default=None,
                   help="print comparison figures of two centerline JSON files")
    args = p.parse_args(argv)
    try:
        with oracle._stdout_to_stderr():
            if args.compare:
                docs = []
                for path in args.compare:
                    try:
                        docs.append(json.loads(Path(path).read_text()))
                    except (OSError, ValueError) as e:
                        raise OracleError(f"{path}: {e}") from None
                res = compare(docs[0], docs[1], args.voxel)
            else:
                if not args.mesh or not args.out:
                    raise OracleError("give MESH -o OUT.json, or --compare OURS.json REF.json")
                V, F = oracle.load_mesh(args.mesh)
                doc = centerline(V, F, args.voxel, mesh_name=str(args.mesh))
                tmp = Path(str(args.out) + ".tmp")
                tmp.write_text(json.dumps(oracle._jsonable(doc)))
                tmp.replace(args.out)
                res = {
                    "voxel": doc["voxel"],
                    "branches": len(doc["branches"]),
                    "junctions": len(doc["junctions"]),
                    "endpoints": len(doc["endpoints"]),
                    "open_ends": sum(1 for e in doc["endpoints"] if e["open_end"]),
                    "components": doc["components"],
                    "length": sum(b["length"] for b in doc["branches"]),
                    "timings": doc["timings"],
                    "seconds": doc["timings"]["total"],
                }
    except OracleError as e:
        print(f"centerline: error: {e}", file=sys.stderr)
        return 1
    except Exception as e:  # library failures: still one line on stderr and exit 1
        print(f"centerline: error: {type(e).__name__}: {e}", file=sys.stderr)
        return 1
    print(json.dumps(oracle._jsonable(res)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
