#!/usr/bin/env python3
"""MeshLib's hole filling as a user runs it, for the speed comparison of benches/repair_real.rs.

`python meshlib_fill.py DAMAGED OUT` reads the mesh with MeshLib's own reader (`loadMesh`), fills
every hole with `fillHoleNicely` under the settings peers.py uses (`nicely_settings`: the
triangulation, subdivision and curvature smoothing MeshLib's own tools use), and writes OUT with
MeshLib's writer (`saveMesh`). Timed as a process, it is what a MeshLib user waits for (Python's
start-up and MeshLib's import included), to set beside our whole `vesselmsr repair` command;
peers.py times the filler call alone.
"""

from __future__ import annotations

import sys

import meshlib.mrmeshpy as mm

# Most edge splits in one fillHoleNicely call (MeshLib's own default is 1000; its tools use
# 20 000; a 1.5-radius chop of the aorta or an open aorta end needs about 500 at the mean edge).
MAX_EDGE_SPLITS = 100_000


def nicely_settings(mesh) -> "mm.FillHoleNicelySettings":
    """fillHoleNicely with triangulation, subdivision to the mesh's mean edge and curvature
    smoothing, the universal fill metric and strong multiple-edge avoidance."""
    settings = mm.FillHoleNicelySettings()
    settings.triangulateOnly = False
    settings.smoothCurvature = True
    settings.triangulateParams.metric = mm.getUniversalMetric(mesh)
    settings.triangulateParams.multipleEdgesResolveMode = (
        mm.FillHoleParams.MultipleEdgesResolveMode.Strong
    )
    settings.subdivideSettings.maxEdgeLen = float(mesh.averageEdgeLength())
    settings.subdivideSettings.maxEdgeSplits = MAX_EDGE_SPLITS
    return settings


def fill_all(mesh, settings) -> tuple[int, int]:
    """Every hole of `mesh` (open vessel ends included) filled in place: (holes, new faces)."""
    holes = mesh.topology.findHoleRepresentiveEdges()
    new_faces = 0
    for e in holes:
        new_faces += mm.fillHoleNicely(mesh, e, settings).count()
    return len(holes), new_faces


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print("usage: meshlib_fill.py DAMAGED OUT", file=sys.stderr)
        return 2
    mesh = mm.loadMesh(argv[0])
    fill_all(mesh, nicely_settings(mesh))
    mesh.pack()
    mm.saveMesh(mesh, argv[1])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
