"""VTK's own readers and writers (python `vtk`, the library ParaView and 3D Slicer are built on)
against vesselmsr's .vtp and .vtk mesh files, through the CLI.

(a) `vesselmsr cap` of the aorta to .stl, .vtp and .vtk: vtkXMLPolyDataReader and vtkPolyDataReader
    read the same triangles as the STL output (point for point, to the STL's float32).
(b) vtkXMLPolyDataWriter with its default settings (zlib-compressed, base64 appended, UInt32
    headers, Int64 connectivity) and vtkPolyDataWriter (legacy 5.1 ASCII, and binary): `vesselmsr
    info --json` reads them with VTK's counts.

The binary is $VESSELMSR_BIN (tests/run_all.sh builds target/ci/vesselmsr before running pytest
and sets it), else target/release/vesselmsr.
"""

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
import vtk
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy

ROOT = Path(__file__).resolve().parent.parent
BIN = Path(os.environ.get("VESSELMSR_BIN", ROOT / "target" / "release" / "vesselmsr"))
AORTA = ROOT / "data" / "aorta_abdominal_open_ends.stl"


def _run(*args):
    if not BIN.exists():
        pytest.fail(f"{BIN} not found: build it with `cargo build --release` or set VESSELMSR_BIN")
    r = subprocess.run([str(BIN), "--quiet", *map(str, args)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return r.stdout


def _stl_triangles(path):
    """Corners of a binary STL, shape (n, 3, 3), float32."""
    data = path.read_bytes()
    n = int(np.frombuffer(data, "<u4", 1, 80)[0])
    rec = np.dtype([("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attr", "<u2")])
    return np.frombuffer(data, rec, n, 84)["corners"]


def _read(reader, path):
    errors = []
    reader.AddObserver("ErrorEvent", lambda o, e: errors.append(e))
    reader.AddObserver("WarningEvent", lambda o, e: errors.append(e))
    reader.SetFileName(str(path))
    reader.Update()
    assert not errors, errors
    return reader.GetOutput()


def _triangles(pd):
    """Corners of the polygons of a vtkPolyData (all triangles), shape (n, 3, 3), float64."""
    polys = pd.GetPolys()
    offsets = vtk_to_numpy(polys.GetOffsetsArray())
    conn = vtk_to_numpy(polys.GetConnectivityArray())
    assert np.all(np.diff(offsets) == 3)
    points = vtk_to_numpy(pd.GetPoints().GetData()).astype(np.float64)
    return points[conn.reshape(-1, 3)]


@pytest.fixture(scope="module")
def capped(tmp_path_factory):
    d = tmp_path_factory.mktemp("cap")
    for ext in ["stl", "vtp", "vtk"]:
        _run("cap", AORTA, "-o", d / f"aorta.{ext}")
    return d


def test_vtk_reads_our_vtp_and_vtk(capped):
    stl = _stl_triangles(capped / "aorta.stl")
    assert len(stl) > 12000  # the aorta's 11,887 triangles and the caps
    vtp = _read(vtk.vtkXMLPolyDataReader(), capped / "aorta.vtp")
    legacy = _read(vtk.vtkPolyDataReader(), capped / "aorta.vtk")
    for name, pd in [("vtp", vtp), ("vtk", legacy)]:
        assert pd.GetNumberOfPolys() == len(stl), name
        assert pd.GetNumberOfCells() == len(stl), name
        assert pd.GetPoints().GetDataType() == vtk.VTK_DOUBLE, name
        tri = _triangles(pd)
        # Float64 in our files; the STL holds the same coordinates rounded to float32.
        assert np.array_equal(tri.astype(np.float32), stl), name
    # The same vertices in both files, bit for bit.
    assert np.array_equal(
        vtk_to_numpy(vtp.GetPoints().GetData()), vtk_to_numpy(legacy.GetPoints().GetData())
    )


def _sphere_with_arrays():
    s = vtk.vtkSphereSource()
    s.SetThetaResolution(24)
    s.SetPhiResolution(13)
    s.Update()
    pd = s.GetOutput()
    detail = numpy_to_vtk(np.linspace(-1, 1, pd.GetNumberOfPoints()).astype(np.float32), deep=True)
    detail.SetName("detail")
    pd.GetPointData().AddArray(detail)
    flag = numpy_to_vtk((np.arange(pd.GetNumberOfCells()) % 2).astype(np.uint8), deep=True)
    flag.SetName("inpainted")
    pd.GetCellData().AddArray(flag)
    return pd


@pytest.mark.parametrize(
    "name, make",
    [
        ("default.vtp", vtk.vtkXMLPolyDataWriter),
        ("legacy_ascii.vtk", vtk.vtkPolyDataWriter),
        ("legacy_binary.vtk", vtk.vtkPolyDataWriter),
        ("legacy_42.vtk", vtk.vtkPolyDataWriter),
    ],
)
def test_we_read_what_vtk_writes(tmp_path, name, make):
    pd = _sphere_with_arrays()
    w = make()
    if name == "legacy_binary.vtk":
        w.SetFileTypeToBinary()
    if name == "legacy_42.vtk":
        w.SetFileVersion(42)
    path = tmp_path / name
    w.SetFileName(str(path))
    w.SetInputData(pd)
    assert w.Write() == 1
    text = path.read_bytes()[:400]
    if name == "default.vtp":
        # VTK's defaults, which the reader must handle.
        assert b'compressor="vtkZLibDataCompressor"' in text and b'header_type="UInt32"' in text
    info = json.loads(_run("info", path, "--json"))
    assert info["vertices"] == pd.GetNumberOfPoints()
    assert info["faces"] == pd.GetNumberOfPolys()
    assert info["watertight"] is True and info["boundary_loops"] == 0
    # The sphere's area (triangulated, radius 0.5), as VTK measures it.
    mass = vtk.vtkMassProperties()
    mass.SetInputData(pd)
    mass.Update()
    assert abs(info["area"] - mass.GetSurfaceArea()) < 1e-6 * mass.GetSurfaceArea()
