"""Repair a cohort of vessel meshes with Dask: every mesh of a folder through
`vesselmsr.repair(..., holes=True)` on the workers, the repaired meshes written beside the
reports, and one summary line per mesh.

    python cohort_dask.py MESH_DIR [-o OUT_DIR] [--units mm] [--unit FILE=UNIT ...]
                          [--scheduler ADDRESS] [--workers N]

Without --scheduler it starts a local cluster (N worker processes, one thread each); with
--scheduler tcp://host:8786 the same code runs on that cluster (the workers need the vesselmsr
wheel installed and MESH_DIR and OUT_DIR on a file system they share with this machine).
Units: every mesh in --units (default mm) except those named by --unit, e.g.
`--unit carotid_bifurcation.stl=m` for the shared carotid, which is in metres.

The task is `repair_one` below: it reads the mesh on the worker, repairs it (the GIL is released
meanwhile), writes the repaired mesh and its JSON report, and sends back only the summary.
"""

import argparse
import json
import sys
import time
from pathlib import Path

import vesselmsr

MESH_SUFFIXES = {".stl", ".obj", ".ply", ".vtp", ".vtk"}


def repair_one(path, units, out_dir):
    """Repairs one mesh file; returns its summary (and writes OUT_DIR/NAME.vtp, NAME.json).
    A mesh that fails gives a summary with its error, so one bad mesh never stops the others."""
    path = Path(path)
    start = time.perf_counter()
    try:
        vertices, faces = vesselmsr.read_mesh(path)
        v, f, report = vesselmsr.repair(vertices, faces, holes=True, units=units)
    except (ValueError, OSError) as e:
        return {"mesh": path.name, "error": str(e)}
    out = Path(out_dir)
    vesselmsr.write_mesh(out / f"{path.stem}.vtp", v, f)
    (out / f"{path.stem}.json").write_text(json.dumps(report, indent=2))
    return {
        "mesh": path.name,
        "units": units,
        "faces": int(f.shape[0]),
        "input_volume": report["input"]["volume"],
        "output_volume": report["output"]["volume"],
        "inpainted_volume": sum(r["inpainted_volume"] for r in report["regions"]),
        "regions": len(report["regions"]),
        "watertight": report["watertight"],
        "notices": report.get("notices", []),
        "seconds": time.perf_counter() - start,
    }


def run_cohort(client, paths, units_of, out_dir, timeout=None):
    """Submits every mesh to the Dask `client` and gathers the summaries, in the paths' order
    (waiting at most `timeout` seconds for each)."""
    futures = [
        client.submit(repair_one, str(p), units_of(p), str(out_dir), pure=False) for p in paths
    ]
    return [f.result(timeout=timeout) for f in futures]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("mesh_dir", type=Path)
    parser.add_argument("-o", "--out-dir", type=Path, default=Path("cohort_repaired"))
    parser.add_argument("--units", default="mm", help="unit of every mesh (default mm)")
    parser.add_argument(
        "--unit", action="append", default=[], metavar="FILE=UNIT", help="one mesh's unit"
    )
    parser.add_argument("--scheduler", help="address of a running Dask scheduler")
    parser.add_argument("--workers", type=int, default=2, help="local worker processes")
    args = parser.parse_args(argv)

    paths = sorted(p for p in args.mesh_dir.iterdir() if p.suffix.lower() in MESH_SUFFIXES)
    if not paths:
        sys.exit(f"no mesh files (.stl, .obj, .ply, .vtp, .vtk) in {args.mesh_dir}")
    overrides = dict(u.split("=", 1) for u in args.unit)
    args.out_dir.mkdir(parents=True, exist_ok=True)

    from dask.distributed import Client, LocalCluster

    start = time.perf_counter()
    if args.scheduler:
        client = Client(args.scheduler)
        cluster = None
    else:
        cluster = LocalCluster(
            n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = Client(cluster)
    try:
        rows = run_cohort(
            client, paths, lambda p: overrides.get(p.name, args.units), args.out_dir.resolve()
        )
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    for r in rows:
        if "error" in r:
            print(f"{r['mesh']}: error: {r['error']}")
        else:
            u = r["units"]
            print(
                f"{r['mesh']}: {r['faces']} faces, volume {r['input_volume']:.6g} -> "
                f"{r['output_volume']:.6g} {u}^3, inpainted {r['inpainted_volume']:.6g} {u}^3 "
                f"in {r['regions']} region(s), watertight {r['watertight']}, {r['seconds']:.1f} s"
            )
    (args.out_dir / "summary.json").write_text(json.dumps(rows, indent=2))
    print(f"{len(rows)} meshes in {time.perf_counter() - start:.1f} s; summary in "
          f"{args.out_dir / 'summary.json'}")
    return 1 if any("error" in r for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
