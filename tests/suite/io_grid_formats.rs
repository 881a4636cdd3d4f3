//! Grid file formats: NumPy .npy with its JSON sidecar and VTK ImageData .vti. Round trips through
//! our readers, and independent checks with NumPy (np.load, np.save) and a plain-Python parse of
//! the .vti (xml.etree for the header, NumPy for the raw appended block), run with the oracle's
//! Python.

use crate::common;
use common::*;
use nalgebra::Point3;
use rand::RngExt;
use vesselmsr::grid::{Grid3, GridTransform};
use vesselmsr::io::{
    npy_sidecar_path, read_npy, read_nrrd, read_vti, write_npy, write_nrrd, write_vti,
};

/// A grid with distinct values (including −0, a subnormal and large magnitudes), non-cubic dims
/// and an origin that is not a round number.
fn sample_grid() -> Grid3 {
    let dims = [7, 5, 3];
    let t = GridTransform::new(Point3::new(-12.345678901234567, 0.1, 1e3 / 7.0), 0.3);
    let mut g = Grid3::new(dims, t, 0.0).unwrap();
    let mut rng = rng(8);
    g.data_mut()
        .iter_mut()
        .for_each(|v| *v = rng.random::<f32>() * 200.0 - 100.0);
    g.set(0, 0, 0, -0.0);
    g.set(1, 0, 0, 1e-40);
    g.set(6, 4, 2, 3.0e38);
    g.set(6, 0, 0, -7.25);
    g
}

/// Nodes to check by index: the 8 corners and a few inner ones.
fn probe_nodes(dims: [usize; 3]) -> Vec<[usize; 3]> {
    let [x, y, z] = dims.map(|d| d - 1);
    let mut v = vec![
        [0, 0, 0],
        [x, 0, 0],
        [0, y, 0],
        [0, 0, z],
        [x, y, 0],
        [x, 0, z],
        [0, y, z],
        [x, y, z],
    ];
    v.extend([[1, 2, 1], [3, 1, 2], [5, 4, 0], [2, 3, 1]]);
    v
}

fn same_bits(a: &Grid3, b: &Grid3) {
    assert_eq!(a.dims(), b.dims());
    assert_eq!(a.transform(), b.transform());
    for (x, y) in a.data().iter().zip(b.data()) {
        assert_eq!(x.to_bits(), y.to_bits());
    }
}

const NP_LOAD: &str = r#"
import json, sys
import numpy as np
a = np.load(sys.argv[1])
side = json.load(open(sys.argv[1] + ".json"))
probes = json.loads(sys.argv[2])
print(json.dumps({
    "shape": list(a.shape),
    "dtype": a.dtype.str,
    "c_contiguous": bool(a.flags["C_CONTIGUOUS"]),
    "values": [float(a[k, j, i]) for i, j, k in probes],
    "first_row": [float(v) for v in a.reshape(-1)[: a.shape[2]]],
    "sidecar": side,
}))
"#;

#[test]
fn npy_round_trips_and_numpy_reads_it_as_k_j_i() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("phi.npy");
    let g = sample_grid();
    write_npy(&path, &g).unwrap();
    assert_eq!(npy_sidecar_path(&path), dir.path().join("phi.npy.json"));
    same_bits(&read_npy(&path).unwrap(), &g);

    let probes = probe_nodes(g.dims());
    let probes_json = serde_json::to_string(&probes).unwrap();
    let v = run_python(NP_LOAD, &[&path, &probes_json]);
    println!("numpy: shape {}, dtype {}", v["shape"], v["dtype"]);
    assert_eq!(
        v["shape"],
        serde_json::json!([3, 5, 7]),
        "shape (nz, ny, nx)"
    );
    assert_eq!(v["dtype"], "<f4");
    assert_eq!(v["c_contiguous"], true);
    for (n, &[i, j, k]) in probes.iter().enumerate() {
        let got = v["values"][n].as_f64().unwrap();
        assert_eq!(got, g.get(i, j, k) as f64, "a[{k}, {j}, {i}]");
    }
    // x is fastest in memory: the first 7 values are nodes (0..7, 0, 0).
    for i in 0..7 {
        assert_eq!(v["first_row"][i].as_f64().unwrap(), g.get(i, 0, 0) as f64);
    }
    let side = &v["sidecar"];
    assert_eq!(side["dims"], serde_json::json!([7, 5, 3]));
    assert_eq!(side["axis_order"], "z,y,x");
    assert_eq!(side["units"], "file units");
    assert_eq!(side["sign"], "negative inside");
    assert_eq!(side["voxel"].as_f64().unwrap(), g.voxel());
    for a in 0..3 {
        assert_eq!(side["origin"][a].as_f64().unwrap(), g.transform().origin[a]);
    }
}

#[test]
fn we_read_what_numpy_saves() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.npy");
    let script = r#"
import json, sys
import numpy as np
d = sys.argv[1]
nz, ny, nx = 4, 6, 9
k, j, i = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
a = (i + 10 * j + 100 * k).astype("<f4")
np.save(d + "/good.npy", a)
side = {"dims": [nx, ny, nz], "origin": [1.0, -2.0, 0.5], "voxel": 0.25,
        "axis_order": "z,y,x", "units": "file units", "sign": "negative inside"}
for name, arr in [("f8", a.astype("<f8")), ("fortran", np.asfortranarray(a)),
                  ("flat", a[0]), ("big", a.astype(">f4"))]:
    np.save(d + "/" + name + ".npy", arr)
    json.dump(side, open(d + "/" + name + ".npy.json", "w"))
json.dump(side, open(d + "/good.npy.json", "w"))
print(json.dumps({"ok": True}))
"#;
    run_python(script, &[&dir.path()]);
    let g = read_npy(&good).unwrap();
    assert_eq!(g.dims(), [9, 6, 4]);
    assert_eq!(g.transform().origin, [1.0, -2.0, 0.5]);
    assert_eq!(g.voxel(), 0.25);
    for [i, j, k] in g.whole_box().nodes() {
        assert_eq!(g.get(i, j, k), (i + 10 * j + 100 * k) as f32);
    }
    for (name, words) in [
        ("f8", "'<f8'"),
        ("fortran", "Fortran"),
        ("flat", "2 dimensions"),
        ("big", "'>f4'"),
    ] {
        let p = dir.path().join(format!("{name}.npy"));
        let e = read_npy(&p).unwrap_err().to_string();
        println!("{name}: {e}");
        assert!(
            e.contains(words) && e.contains(&format!("{name}.npy")),
            "{e}"
        );
    }
}

#[test]
fn npy_reader_refuses_broken_files() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("phi.npy");
    let g = sample_grid();
    write_npy(&path, &g).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let sidecar = std::fs::read_to_string(npy_sidecar_path(&path)).unwrap();

    let cases: Vec<(&str, Vec<u8>, String, &str)> = vec![
        (
            "truncated data",
            bytes[..bytes.len() - 4].to_vec(),
            sidecar.clone(),
            "bytes of data",
        ),
        (
            "extra data",
            [&bytes[..], &[0u8; 4]].concat(),
            sidecar.clone(),
            "bytes of data",
        ),
        (
            "bad magic",
            [b"NUMPY!", &bytes[6..]].concat(),
            sidecar.clone(),
            "magic",
        ),
        (
            "truncated header",
            bytes[..40].to_vec(),
            sidecar.clone(),
            "header",
        ),
        (
            "sidecar dims",
            bytes.clone(),
            sidecar.replace("\n    7,", "\n    8,"),
            "do not match",
        ),
        (
            "sidecar voxel",
            bytes.clone(),
            sidecar.replace("0.3", "-0.3"),
            "voxel",
        ),
        ("sidecar junk", bytes.clone(), "{".into(), "sidecar"),
    ];
    for (what, npy, side, words) in cases {
        std::fs::write(&path, &npy).unwrap();
        std::fs::write(npy_sidecar_path(&path), &side).unwrap();
        let e = read_npy(&path).unwrap_err().to_string();
        println!("{what}: {e}");
        assert!(e.contains(words) && e.contains("phi.npy"), "{what}: {e}");
    }
    std::fs::write(&path, &bytes).unwrap();
    std::fs::remove_file(npy_sidecar_path(&path)).unwrap();
    let e = read_npy(&path).unwrap_err().to_string();
    assert!(e.contains("phi.npy.json"), "missing sidecar: {e}");
}

#[test]
fn failed_writes_leave_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let g = sample_grid();
    // The sidecar cannot be written (a folder is in the way): no .npy either.
    let path = dir.path().join("phi.npy");
    std::fs::create_dir(npy_sidecar_path(&path)).unwrap();
    assert!(write_npy(&path, &g).is_err());
    assert!(
        !path.exists(),
        "the .npy was removed after the sidecar failed"
    );
    // A missing folder: nothing written, the error names the file.
    for path in [
        dir.path().join("none/phi.npy"),
        dir.path().join("none/phi.vti"),
    ] {
        let e = if path.extension().unwrap() == "npy" {
            write_npy(&path, &g)
        } else {
            write_vti(&path, &g)
        }
        .unwrap_err()
        .to_string();
        assert!(e.contains("phi."), "{e}");
        assert!(!dir.path().join("none").exists());
    }
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(
        leftovers,
        vec![std::ffi::OsString::from("phi.npy.json")],
        "only the folder we made"
    );
}

const VTI_PARSE: &str = r#"
import json, sys
import xml.etree.ElementTree as ET
import numpy as np
raw = open(sys.argv[1], "rb").read()
at = raw.index(b"<AppendedData")
# The XML part must be well-formed: close it without the binary section and parse it.
head = raw[:at] + b'<AppendedData encoding="raw"/></VTKFile>'
root = ET.fromstring(head)
image = root.find("ImageData")
array = image.find("Piece/PointData/DataArray")
underscore = raw.index(b"_", at)
offset = int(array.get("offset"))
block = raw[underscore + 1 + offset:]
size = int(np.frombuffer(block[:8], "<u8")[0])
ext = [int(v) for v in image.get("WholeExtent").split()]
nx, ny, nz = ext[1] - ext[0] + 1, ext[3] - ext[2] + 1, ext[5] - ext[4] + 1
a = np.frombuffer(block[8:8 + size], "<f4").reshape(nz, ny, nx)
tail = block[8 + size:].decode().split()
probes = json.loads(sys.argv[2])
print(json.dumps({
    "root": dict(root.attrib),
    "extent": ext,
    "piece_extent": image.find("Piece").get("Extent"),
    "origin": [float(v) for v in image.get("Origin").split()],
    "spacing": [float(v) for v in image.get("Spacing").split()],
    "scalars": image.find("Piece/PointData").get("Scalars"),
    "array": dict(array.attrib),
    "size": size,
    "values": [float(a[k, j, i]) for i, j, k in probes],
    "min": float(np.nanmin(a)), "max": float(np.nanmax(a)),
    "tail": tail,
}))
"#;

#[test]
fn vti_round_trips_and_parses_independently() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("phi.vti");
    let g = sample_grid();
    write_vti(&path, &g).unwrap();
    same_bits(&read_vti(&path).unwrap(), &g);

    let probes = probe_nodes(g.dims());
    let probes_json = serde_json::to_string(&probes).unwrap();
    let v = run_python(VTI_PARSE, &[&path, &probes_json]);
    println!("vti header: {} {}", v["root"], v["array"]);
    assert_eq!(v["root"]["type"], "ImageData");
    assert_eq!(v["root"]["byte_order"], "LittleEndian");
    assert_eq!(v["root"]["header_type"], "UInt64");
    assert_eq!(v["extent"], serde_json::json!([0, 6, 0, 4, 0, 2]));
    assert_eq!(v["piece_extent"], "0 6 0 4 0 2");
    for a in 0..3 {
        assert_eq!(
            v["origin"][a].as_f64().unwrap(),
            g.transform().origin[a],
            "Origin exact"
        );
        assert_eq!(v["spacing"][a].as_f64().unwrap(), g.voxel());
    }
    assert_eq!(v["scalars"], "phi");
    assert_eq!(v["array"]["Name"], "phi");
    assert_eq!(v["array"]["type"], "Float32");
    assert_eq!(v["array"]["format"], "appended");
    assert_eq!(v["size"], 7 * 5 * 3 * 4);
    for (n, &[i, j, k]) in probes.iter().enumerate() {
        assert_eq!(
            v["values"][n].as_f64().unwrap(),
            g.get(i, j, k) as f64,
            "node {i},{j},{k}"
        );
    }
    // RangeMin/RangeMax are the f32 extremes (printed shortest, so read back as f32).
    for (attr, key) in [("RangeMin", "min"), ("RangeMax", "max")] {
        let text = v["array"][attr].as_str().unwrap();
        assert_eq!(
            text.parse::<f32>().unwrap(),
            v[key].as_f64().unwrap() as f32,
            "{attr}"
        );
    }
    assert_eq!(
        v["tail"],
        serde_json::json!(["</AppendedData>", "</VTKFile>"])
    );
}

#[test]
fn vti_reader_refuses_broken_files() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("phi.vti");
    write_vti(&path, &sample_grid()).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    // The text before the binary block: up to the '_' after <AppendedData ...>.
    let appended = bytes
        .windows(13)
        .position(|w| w == b"<AppendedData")
        .unwrap();
    let text_end = appended + bytes[appended..].iter().position(|&b| b == b'_').unwrap();
    let header = String::from_utf8_lossy(&bytes[..text_end]).into_owned();
    let with_header = |h: String| [h.as_bytes(), &bytes[text_end..]].concat();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("truncated", bytes[..bytes.len() - 60].to_vec(), "shorter"),
        ("no data", bytes[..200].to_vec(), "AppendedData"),
        (
            "base64",
            with_header(header.replace("encoding=\"raw\"", "encoding=\"base64\"")),
            "base64",
        ),
        (
            "Float64",
            with_header(header.replace("\"Float32\"", "\"Float64\"")),
            "Float64",
        ),
        (
            "UInt32 header",
            with_header(header.replace("\"UInt64\"", "\"UInt32\"")),
            "UInt32",
        ),
        (
            "spacing",
            with_header(header.replace("Spacing=\"0.3 0.3", "Spacing=\"0.3 0.4")),
            "spacing",
        ),
        (
            "extent",
            with_header(header.replace("0 6 0 4", "0 7 0 4")),
            "bytes",
        ),
        ("text", b"hello".to_vec(), "AppendedData"),
    ];
    for (what, content, words) in cases {
        std::fs::write(&path, &content).unwrap();
        let e = read_vti(&path).unwrap_err().to_string();
        println!("{what}: {e}");
        assert!(e.contains(words) && e.contains("phi.vti"), "{what}: {e}");
    }
}

const VTK_READ: &str = r#"
import json, sys
try:
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
except ImportError:
    print(json.dumps({"vtk": None}))
    sys.exit(0)
r = vtk.vtkXMLImageDataReader()
messages = []
r.AddObserver("ErrorEvent", lambda o, e: messages.append(e))
r.AddObserver("WarningEvent", lambda o, e: messages.append(e))
r.SetFileName(sys.argv[1])
r.Update()
img = r.GetOutput()
s = img.GetPointData().GetScalars()
print(json.dumps({
    "vtk": vtk.vtkVersion.GetVTKVersion(),
    "messages": messages,
    "dims": list(img.GetDimensions()),
    "origin": list(img.GetOrigin()),
    "spacing": list(img.GetSpacing()),
    "name": s.GetName(),
    "type": s.GetDataTypeAsString(),
    "values": [float(v) for v in vtk_to_numpy(s)],
    "point_last": list(img.GetPoint(img.GetNumberOfPoints() - 1)),
}))
"#;

/// VTK's own reader (the one ParaView uses), when the oracle's Python has the `vtk` package
/// (not in reference/requirements.txt: the check is skipped with a notice otherwise).
#[test]
fn vtk_reads_the_vti_when_available() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("phi.vti");
    let g = sample_grid();
    write_vti(&path, &g).unwrap();
    let v = run_python(VTK_READ, &[&path]);
    if v["vtk"].is_null() {
        skip("the oracle's Python has no vtk package");
        return;
    }
    println!(
        "VTK {}: dims {} origin {}",
        v["vtk"], v["dims"], v["origin"]
    );
    assert_eq!(
        v["messages"],
        serde_json::json!([]),
        "no VTK errors or warnings"
    );
    assert_eq!(v["dims"], serde_json::json!([7, 5, 3]));
    assert_eq!(v["name"], "phi");
    assert_eq!(v["type"], "float");
    for a in 0..3 {
        assert_eq!(v["origin"][a].as_f64().unwrap(), g.transform().origin[a]);
        assert_eq!(v["spacing"][a].as_f64().unwrap(), g.voxel());
    }
    let last = g.world(6, 4, 2);
    for a in 0..3 {
        assert!((v["point_last"][a].as_f64().unwrap() - last[a]).abs() < 1e-12);
    }
    let values: Vec<f32> = v["values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap() as f32)
        .collect();
    assert_eq!(values.len(), g.data().len());
    for (a, b) in values.iter().zip(g.data()) {
        assert_eq!(
            a.to_bits(),
            b.to_bits(),
            "VTK point order is x fastest, like Grid3"
        );
    }
}

/// ITK's NRRD reader (the one 3D Slicer loads `.nrrd` volumes with), through SimpleITK.
const ITK_READ: &str = r#"
import json, sys
import SimpleITK as sitk
img = sitk.ReadImage(sys.argv[1])
a = sitk.GetArrayFromImage(img)
probes = json.loads(sys.argv[2])
print(json.dumps({
    "size": list(img.GetSize()),
    "origin": list(img.GetOrigin()),
    "spacing": list(img.GetSpacing()),
    "direction": list(img.GetDirection()),
    "pixel": img.GetPixelIDTypeAsString(),
    "values": [float(a[k, j, i]) for i, j, k in probes],
}))
"#;

#[test]
fn nrrd_round_trips_and_itk_reads_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("phi.nrrd");
    let g = sample_grid();
    write_nrrd(&path, &g).unwrap();
    same_bits(&read_nrrd(&path).unwrap(), &g);

    let probes = probe_nodes(g.dims());
    let probes_json = serde_json::to_string(&probes).unwrap();
    let v = run_python(ITK_READ, &[&path, &probes_json]);
    println!("ITK: {v}");
    assert_eq!(v["size"], serde_json::json!([7, 5, 3]));
    assert_eq!(v["pixel"], "32-bit float");
    assert_eq!(
        v["direction"],
        serde_json::json!([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])
    );
    for a in 0..3 {
        assert_eq!(v["origin"][a].as_f64().unwrap(), g.transform().origin[a]);
        assert_eq!(v["spacing"][a].as_f64().unwrap(), g.voxel());
    }
    for (n, &[i, j, k]) in probes.iter().enumerate() {
        assert_eq!(v["values"][n].as_f64().unwrap(), g.get(i, j, k) as f64);
    }
}

#[test]
fn nrrd_reader_refuses_broken_files() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("phi.nrrd");
    write_nrrd(&path, &sample_grid()).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let end = bytes.windows(2).position(|w| w == b"\n\n").unwrap();
    let header = String::from_utf8_lossy(&bytes[..end]).into_owned();
    let with_header = |h: String| [h.as_bytes(), &bytes[end..]].concat();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "truncated",
            bytes[..bytes.len() - 8].to_vec(),
            "bytes of data",
        ),
        ("no header end", bytes[..end].to_vec(), "blank line"),
        ("not nrrd", b"P6\n7 5\n".to_vec(), "not a NRRD"),
        (
            "gzip",
            with_header(header.replace("encoding: raw", "encoding: gzip")),
            "gzip",
        ),
        (
            "double",
            with_header(header.replace("type: float", "type: double")),
            "double",
        ),
        (
            "rotated",
            with_header(header.replace("(0,0.3,0)", "(0.3,0,0)")),
            "axis-aligned",
        ),
    ];
    for (what, data, word) in cases {
        std::fs::write(&path, data).unwrap();
        let e = read_nrrd(&path).unwrap_err().to_string();
        assert!(e.contains("phi.nrrd") && e.contains(word), "{what}: {e}");
    }
}
