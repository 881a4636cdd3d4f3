#!/usr/bin/env python3
"""pymeshlab baselines for the vessel repair (issue 6): what a user gets without vesselmsr.

* close-holes  MeshLab's hole filling (`meshing_close_holes`), with the largest hole size set
               from the mesh's boundary edge count so every hole is a candidate (open vessel ends
               included: the baseline cannot tell an end from a hole);
* poisson      screened Poisson surface reconstruction (Kazhdan and Hoppe 2013,
               `generate_surface_reconstruction_screened_poisson`) from the mesh's vertices and
               their area-weighted normals (faces are dropped: a point cloud with normals).

Meshes are read and written by reference/oracle.py's readers (no repair on load); the result is
judged by the oracle's `check` (manifold3d verdict, manifold3d volume). Use as a module or as a
CLI: `python baseline.py close-holes|poisson IN OUT [options]`, which prints one JSON object:
{method, input, output, seconds (the pymeshlab filter only), vertices, faces, boundary_loops_in,
boundary_loops, watertight, manifold_status, volume (manifold3d, null unless watertight), ...}.
Errors print one line on stderr and exit 1.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import oracle  # noqa: E402
from oracle import OracleError  # noqa: E402


def _meshset(V: np.ndarray, F: np.ndarray, normals: np.ndarray | None = None):
    import pymeshlab

    ms = pymeshlab.MeshSet()
    if normals is None:
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)))
    else:
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, v_normals_matrix=normals))
    return ms


def _loops(ms) -> int:
    return int(ms.get_topological_measures()["number_holes"])


def _judge(V: np.ndarray, F: np.ndarray) -> dict:
    """manifold3d verdict and volume of the result (volume only when it is watertight)."""
    if len(F) == 0:
        return {"watertight": False, "manifold_status": "NoTriangles", "volume": None}
    c = oracle.check(V, F)
    ok = c["manifold_status"] == "NoError"
    return {
        "watertight": ok,
        "manifold_status": c["manifold_status"],
        "volume": abs(c["manifold_volume"]) if ok else None,
        "boundary_edges": c["boundary_edges"],
    }


def vertex_normals(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals (zero for vertices no face uses); they follow the faces'
    winding, so an outward-facing mesh gives outward normals."""
    tri = V[F]
    fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])  # length = 2·area
    N = np.zeros_like(V)
    for k in range(3):
        np.add.at(N, F[:, k], fn)
    ln = np.linalg.norm(N, axis=1, keepdims=True)
    return np.divide(N, ln, out=np.zeros_like(N), where=ln > 0)


def close_holes(in_path, out_path, maxholesize: int | None = None) -> dict:
    """pymeshlab `meshing_close_holes` on the mesh at `in_path`, written to `out_path`.

    maxholesize is in boundary edges; None means the mesh's boundary edge count + 1 (every hole
    and every open end is a candidate). MeshLab skips fills that would self-intersect.
    """
    V, F = oracle.load_mesh(in_path)
    if len(F) == 0:
        raise OracleError(f"{in_path}: mesh has no triangles")
    ms = _meshset(V, F)
    loops_in = _loops(ms)
    boundary_edges_in = int(ms.get_topological_measures()["boundary_edges"])
    if maxholesize is None:
        maxholesize = boundary_edges_in + 1
    if maxholesize < 3:
        raise OracleError("maxholesize must be at least 3 boundary edges")
    t0 = time.perf_counter()
    ms.meshing_close_holes(maxholesize=int(maxholesize))
    seconds = time.perf_counter() - t0
    return _result(
        ms,
        out_path,
        method="close-holes",
        input=str(in_path),
        maxholesize=int(maxholesize),
        seconds=seconds,
        boundary_edges_in=boundary_edges_in,
        boundary_loops_in=loops_in,
    )


def _result(ms, out_path, **fields) -> dict:
    """Writes the current mesh of `ms` to `out_path` and returns `fields` with its measures."""
    m = ms.current_mesh()
    V2 = np.array(m.vertex_matrix(), np.float64)
    F2 = np.array(m.face_matrix(), np.int64)
    oracle.save_mesh(out_path, V2, F2)
    return {
        **fields,
        "output": str(out_path),
        "vertices": int(len(V2)),
        "faces": int(len(F2)),
        "boundary_loops": _loops(ms) if len(F2) else 0,
        **_judge(V2, F2),
    }


def poisson(in_path, out_path, depth: int = 8) -> dict:
    """Screened Poisson reconstruction (octree depth `depth`) from the vertices of the mesh at
    `in_path` with their area-weighted normals, written to `out_path`."""
    if not 1 <= depth <= 16:
        raise OracleError("depth must be between 1 and 16")
    V, F = oracle.load_mesh(in_path)
    if len(F) == 0:
        raise OracleError(f"{in_path}: mesh has no triangles")
    loops_in = _loops(_meshset(V, F))
    N = vertex_normals(V, F)
    used = np.linalg.norm(N, axis=1) > 0
    ms = _meshset(V[used], F, normals=N[used])
    t0 = time.perf_counter()
    ms.generate_surface_reconstruction_screened_poisson(depth=int(depth), preclean=True)
    seconds = time.perf_counter() - t0
    return _result(
        ms,
        out_path,
        method="poisson",
        input=str(in_path),
        depth=int(depth),
        seconds=seconds,
        points=int(used.sum()),
        boundary_loops_in=loops_in,
    )


def _parser() -> argparse.ArgumentParser:
    p = oracle._Parser(prog="baseline.py", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="command", required=True, parser_class=oracle._Parser)
    s = sub.add_parser("close-holes", help="pymeshlab meshing_close_holes")
    s.add_argument("input")
    s.add_argument("output", help="output mesh (.stl, .obj or .ply)")
    s.add_argument(
        "--maxholesize",
        type=int,
        default=None,
        help="largest hole closed, in boundary edges (default: boundary edge count + 1)",
    )
    s = sub.add_parser("poisson", help="pymeshlab screened Poisson reconstruction")
    s.add_argument("input")
    s.add_argument("output", help="output mesh (.stl, .obj or .ply)")
    s.add_argument("--depth", type=int, default=8, help="octree depth (default 8)")
    return p


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        with oracle._stdout_to_stderr():
            if args.command == "close-holes":
                res = close_holes(args.input, args.output, maxholesize=args.maxholesize)
            else:
                res = poisson(args.input, args.output, depth=args.depth)
    except OracleError as e:
        print(f"baseline: error: {e}", file=sys.stderr)
        return 1
    except Exception as e:  # library failures: still one line on stderr and exit 1
        print(f"baseline: error: {type(e).__name__}: {e}", file=sys.stderr)
        return 1
    print(json.dumps(oracle._jsonable(res)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
