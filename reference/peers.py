#!/usr/bin/env python3
"""Peer hole fillers on one damaged mesh, for benches/repair_real.rs (issue 21).

`python peers.py DAMAGED.stl --out-dir DIR [--tools meshlib,pymeshfix,pymeshlab]` runs each peer on
the same damaged mesh and writes DIR/meshlib.stl, DIR/pymeshfix.stl, DIR/pymeshlab.stl and
DIR/peers.json; the same JSON is printed as one line on stdout. Per tool: "seconds" (the filler
call only), "seconds_with_io" (the mesh handed to the library, filled, taken back and written),
"output" (the file, or null), "error" (null, or what went wrong), plus a few counts; at the top,
"seconds_script" (this script's wall time from its first line, imports included). peers.json is
rewritten before each tool starts, with that tool marked as not finished, so that a tool that
kills the process (a crash in its C++) still leaves the others' results and names itself.

The peers, each as a user would call it:
* meshlib (PyPI `meshlib`, MeshInspector's MeshLib): every hole (`findHoleRepresentiveEdges`,
  open vessel ends included) filled by `fillHoleNicely` with triangulation, subdivision and
  curvature smoothing on (`FillHoleNicelySettings`: `triangulateOnly = False`,
  `smoothCurvature = True`), the universal fill metric and strong multiple-edge avoidance for the
  triangulation, new edges no longer than the input's mean edge (so the patch is as dense as
  the wall around it; the default of 0 splits until the split budget is spent) and a split
  budget large enough for any hole here — the settings MeshLib itself uses when it fills holes
  nicely inside its own tools;
* pymeshfix (`MeshFix(v, f).repair()`, its defaults: holes filled, all but the largest
  component removed, self-intersections removed);
* pymeshlab (`meshing_close_holes` with `maxholesize` above the mesh's boundary edge count, so
  any hole is a candidate; its other defaults, including the refusal of patches that would
  self-intersect), through `oracle.close_holes`, whose "seconds" includes building the
  MeshSet (milliseconds).

The mesh is read by oracle.py's reader (no repair: STL corners welded on bit-equal coordinates).
Versions: reference/requirements-peers.txt (exact pins; benches/repair_real.rs installs it into
reference/.venv on demand; not part of requirements.txt, so the test suite stays quick).
"""

from __future__ import annotations

import time

_T0 = time.perf_counter()

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import traceback  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from oracle import _jsonable, _stdout_to_stderr, close_holes, load_mesh, save_mesh  # noqa: E402

TOOLS = ("meshlib", "pymeshfix", "pymeshlab")

def run_meshlib(V: np.ndarray, F: np.ndarray) -> dict:
    import meshlib.mrmeshnumpy as mn

    from meshlib_fill import fill_all, nicely_settings

    mesh = mn.meshFromFacesVerts(F.astype(np.int32), V.astype(np.float32))
    settings = nicely_settings(mesh)
    t = time.perf_counter()
    holes, new_faces = fill_all(mesh, settings)
    seconds = time.perf_counter() - t
    mesh.pack()
    return {
        "seconds": seconds,
        "holes": holes,
        "new_faces": new_faces,
        "V": np.asarray(mn.getNumpyVerts(mesh), np.float64),
        "F": np.asarray(mn.getNumpyFaces(mesh.topology), np.int64),
    }


def run_pymeshfix(V: np.ndarray, F: np.ndarray) -> dict:
    import pymeshfix

    fix = pymeshfix.MeshFix(V, F.astype(np.int32))
    t = time.perf_counter()
    fix.repair()
    seconds = time.perf_counter() - t
    return {
        "seconds": seconds,
        "V": np.asarray(fix.points, np.float64),
        "F": np.asarray(fix.faces, np.int64),
    }


def run_pymeshlab(V: np.ndarray, F: np.ndarray) -> dict:
    return close_holes(V, F)


RUNNERS = {"meshlib": run_meshlib, "pymeshfix": run_pymeshfix, "pymeshlab": run_pymeshlab}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="peers.py", description=__doc__.split("\n\n")[0])
    p.add_argument("mesh", help="the damaged mesh (.stl, .obj or .ply)")
    p.add_argument("--out-dir", required=True, help="folder for TOOL.stl and peers.json")
    p.add_argument("--tools", default=",".join(TOOLS), help="comma-separated subset of " + ", ".join(TOOLS))
    args = p.parse_args(argv)
    tools = [t for t in args.tools.split(",") if t]
    unknown = [t for t in tools if t not in RUNNERS]
    if unknown:
        p.error(f"unknown tool(s) {unknown}; known: {', '.join(TOOLS)}")
    out_dir = Path(args.out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    report: dict = {"input": str(args.mesh), "tools": {}}

    def write() -> None:
        report["seconds_script"] = time.perf_counter() - _T0
        (out_dir / "peers.json").write_text(json.dumps(_jsonable(report), indent=1) + "\n")

    V, F = load_mesh(args.mesh)
    report["vertices"], report["faces"] = len(V), len(F)
    for tool in tools:
        report["tools"][tool] = {
            "output": None,
            "error": "did not finish: the process died in this tool",
        }
        write()
        out = out_dir / f"{tool}.stl"
        entry: dict = {"output": None, "error": None}
        t = time.perf_counter()
        try:
            with _stdout_to_stderr():
                res = RUNNERS[tool](V, F)
            if len(res["F"]) == 0:
                raise RuntimeError("the output has no triangle")
            if not np.isfinite(res["V"]).all():
                raise RuntimeError("the output has non-finite vertex coordinates")
            save_mesh(out, res["V"], res["F"])
            entry.update({k: v for k, v in res.items() if k not in ("V", "F")})
            entry["output"] = str(out)
            entry["vertices"], entry["faces"] = len(res["V"]), len(res["F"])
        except Exception as e:  # a peer's failure is a result to report, not the script's
            traceback.print_exc(file=sys.stderr)
            entry["error"] = f"{type(e).__name__}: {e}"
        entry["seconds_with_io"] = time.perf_counter() - t
        report["tools"][tool] = entry
        write()
    print(json.dumps(_jsonable(report)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
