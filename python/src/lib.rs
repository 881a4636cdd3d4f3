//! The Python module `vesselmsr`: the library's repair, capping, re-meshing and mesh I/O on numpy
//! arrays (vertices (n, 3) float64 or float32, faces (m, 3) integers), built by maturin as an
//! abi3 wheel.
//!
//! `repair` runs [`vesselmsr::inpaint::pipeline::repair_vessel`], the same function as
//! `vesselmsr repair`, and returns its report as a dict equal to the CLI's JSON report (the same
//! serde struct, through `json.loads`; without the file paths and the `read` timing). `cap` runs
//! [`vesselmsr::mesh::cap::cap_mesh`] as `vesselmsr cap` does (its dict is all of `cap --json`),
//! `remesh` runs [`vesselmsr::levelset::remesh::remesh_mesh`], the work of `vesselmsr remesh`
//! (its dict is `remesh --json` without the timings). The work runs with the GIL released, so
//! threads (and Dask's threaded workers) repair in parallel.
//! Arrays are checked before anything runs (shape, dtype, indices in range, finite coordinates,
//! a usable triangle); the library's errors become `ValueError` (bad options and arrays),
//! `OSError` (files) or `vesselmsr.VesselmsrError` (a subclass of `ValueError`: the mesh could
//! not be repaired or read); its notices become `vesselmsr.VesselmsrWarning` warnings.

use numpy::{
    PyArray1, PyArray2, PyArrayDescrMethods, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::create_exception;
use pyo3::exceptions::{PyOSError, PyTypeError, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyString};
use std::ffi::CString;
use std::path::PathBuf;
use vesselmsr::grid::GridOptions;
use vesselmsr::inpaint::pipeline::{repair_vessel, RepairEvent, VesselRepair};
use vesselmsr::inpaint::region::Ball;
use vesselmsr::inpaint::repair::{InpaintMethod, RepairOptions};
use vesselmsr::levelset::remesh::{remesh_mesh, RemeshEvent, RemeshOptions};
use vesselmsr::mesh::cap::{cap_mesh, CapOptions};
use vesselmsr::{Error, TriMesh};

create_exception!(
    vesselmsr,
    VesselmsrError,
    PyValueError,
    "A mesh vesselmsr could not read, repair or write (the library's message)."
);
create_exception!(
    vesselmsr,
    VesselmsrWarning,
    PyUserWarning,
    "A notice of vesselmsr (what the CLI prints on stderr)."
);

/// The library's error as a Python exception (see the module doc).
fn py_error(e: Error) -> PyErr {
    match e {
        Error::Io { .. } => PyOSError::new_err(e.to_string()),
        Error::BadOption {
            option: "regions", ..
        } => PyValueError::new_err(
            "no region to repair: give regions=[(x, y, z, r), ...] or a regions file, \
             holes=True or stenoses=True",
        ),
        Error::BadOption { .. } | Error::InvalidMesh(_) => PyValueError::new_err(e.to_string()),
        e => VesselmsrError::new_err(e.to_string()),
    }
}

/// Issues each notice as a `VesselmsrWarning`.
fn warn_all(py: Python<'_>, notices: &[String]) -> PyResult<()> {
    let category = py.get_type::<VesselmsrWarning>();
    for n in notices {
        let text = CString::new(n.replace('\0', " ")).unwrap_or_default();
        PyErr::warn(py, &category, &text, 2)?;
    }
    Ok(())
}

/// Runs `work` with the GIL released, collecting the notices it pushes, then raises them as
/// warnings; the library's error becomes a Python exception. Returns `work`'s result and its
/// report as JSON text (`report`, `serde_json::to_string` of the report struct).
fn detached<T: Send>(
    py: Python<'_>,
    work: impl FnOnce(&mut Vec<String>) -> vesselmsr::Result<T> + Send,
    report: impl FnOnce(&T) -> serde_json::Result<String> + Send,
) -> PyResult<(T, String)> {
    let mut notices = Vec::new();
    let outcome = py.detach(|| {
        work(&mut notices).and_then(|done| {
            let text = report(&done).map_err(|e| Error::Geometry(format!("report: {e}")))?;
            Ok((done, text))
        })
    });
    warn_all(py, &notices)?;
    outcome.map_err(py_error)
}

/// `obj` as a numpy array (any array-like), checked to be 2-D with 3 columns.
fn as_rows_of_3<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<Bound<'py, PyUntypedArray>> {
    let py = obj.py();
    let array = py.import("numpy")?.call_method1("asarray", (obj,))?;
    let array = array
        .cast_into::<PyUntypedArray>()
        .map_err(|_| PyTypeError::new_err(format!("{what} must be a numpy array")))?;
    let shape = array.shape();
    if shape.len() != 2 || shape[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "{what} must have shape ({}, 3), got {shape:?}",
            if what == "faces" { "m" } else { "n" }
        )));
    }
    Ok(array)
}

/// The vertices as points: (n, 3) float64 or float32 (float32 widened exactly; either byte
/// order).
fn vertices_from(obj: &Bound<'_, PyAny>) -> PyResult<Vec<[f64; 3]>> {
    let array = as_rows_of_3(obj, "vertices")?;
    let dtype = array.dtype();
    if !(dtype.kind() == b'f' && matches!(dtype.itemsize(), 4 | 8)) {
        return Err(PyTypeError::new_err(format!(
            "vertices must be float64 or float32, got {}",
            dtype.str()?
        )));
    }
    // Native float64: no copy.
    let array = obj
        .py()
        .import("numpy")?
        .call_method1("asarray", (array, "float64"))?;
    let array = array.cast::<PyArray2<f64>>()?.readonly();
    Ok(array
        .as_array()
        .rows()
        .into_iter()
        .map(|r| [r[0], r[1], r[2]])
        .collect())
}

/// The faces as vertex-index triples: (m, 3) of any integer dtype, every index in 0..n.
fn faces_from(obj: &Bound<'_, PyAny>, n: usize) -> PyResult<Vec<[u32; 3]>> {
    let array = as_rows_of_3(obj, "faces")?;
    let dtype = array.dtype();
    let check = |k: usize, i: i128| -> PyResult<u32> {
        if i < 0 {
            return Err(PyValueError::new_err(format!(
                "faces[{k}] has a negative index {i}"
            )));
        }
        if i >= n as i128 {
            return Err(PyValueError::new_err(format!(
                "faces[{k}] references vertex {i} but vertices has only {n} rows"
            )));
        }
        Ok(i as u32)
    };
    let mut faces = Vec::with_capacity(array.shape()[0]);
    match dtype.kind() {
        b'i' => {
            let a = array.call_method1("astype", ("int64",))?;
            let a = a.cast::<PyArray2<i64>>()?.readonly();
            for (k, r) in a.as_array().rows().into_iter().enumerate() {
                faces.push([
                    check(k, r[0].into())?,
                    check(k, r[1].into())?,
                    check(k, r[2].into())?,
                ]);
            }
        }
        b'u' => {
            let a = array.call_method1("astype", ("uint64",))?;
            let a = a.cast::<PyArray2<u64>>()?.readonly();
            for (k, r) in a.as_array().rows().into_iter().enumerate() {
                faces.push([
                    check(k, r[0].into())?,
                    check(k, r[1].into())?,
                    check(k, r[2].into())?,
                ]);
            }
        }
        _ => {
            return Err(PyTypeError::new_err(format!(
                "faces must be integers, got {}",
                dtype.str()?
            )))
        }
    }
    Ok(faces)
}

/// A mesh from arrays, checked as a mesh read from a file is.
fn mesh_from(vertices: &Bound<'_, PyAny>, faces: &Bound<'_, PyAny>) -> PyResult<TriMesh> {
    let points = vertices_from(vertices)?;
    if points.len() > u32::MAX as usize {
        return Err(PyValueError::new_err(format!(
            "{} vertices: at most {} are taken",
            points.len(),
            u32::MAX
        )));
    }
    let faces = faces_from(faces, points.len())?;
    let mesh = TriMesh::new(points.into_iter().map(Into::into).collect(), faces);
    vesselmsr::io::check_mesh(&mesh).map_err(py_error)?;
    Ok(mesh)
}

/// A mesh as numpy arrays: vertices float64 (n, 3), faces int64 (m, 3).
type MeshArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>);

/// What `repair`, `cap` and `remesh` return: the mesh's arrays and the report dict.
type Repaired<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<i64>>,
    Bound<'py, PyAny>,
);

/// The mesh as (vertices float64 (n, 3), faces int64 (m, 3)).
fn arrays_of<'py>(py: Python<'py>, mesh: &TriMesh) -> PyResult<MeshArrays<'py>> {
    let v: Vec<f64> = mesh.vertices.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    let f: Vec<i64> = mesh.faces.iter().flat_map(|t| t.map(i64::from)).collect();
    let v = PyArray1::from_vec(py, v).reshape([mesh.num_vertices(), 3])?;
    let f = PyArray1::from_vec(py, f).reshape([mesh.num_faces(), 3])?;
    Ok((v, f))
}

/// A JSON text as Python objects (`json.loads`).
fn from_json<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}

/// `False`/`None` → None, `True` → `default`, a number → that number.
fn flag_or_number(
    obj: Option<&Bound<'_, PyAny>>,
    name: &str,
    default: f64,
) -> PyResult<Option<f64>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(None);
    };
    if obj.is_instance_of::<PyBool>() {
        return Ok(obj.extract::<bool>()?.then_some(default));
    }
    obj.extract::<f64>()
        .map(Some)
        .map_err(|_| PyTypeError::new_err(format!("{name} must be a bool or a number")))
}

/// The regions argument: a regions file (str or path) or a sequence of (x, y, z, r).
fn regions_from(obj: Option<&Bound<'_, PyAny>>) -> PyResult<(Vec<Ball>, Option<PathBuf>)> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok((Vec::new(), None));
    };
    if obj.is_instance_of::<PyString>() || obj.hasattr("__fspath__")? {
        return Ok((Vec::new(), Some(obj.extract::<PathBuf>()?)));
    }
    let mut balls = Vec::new();
    for (k, item) in obj.try_iter()?.enumerate() {
        let item = item?;
        // A row of a numpy array is no Python sequence: its list is.
        let item = match item.hasattr("tolist")? {
            true => item.call_method0("tolist")?,
            false => item,
        };
        let [x, y, z, r] = item.extract::<[f64; 4]>().map_err(|_| {
            PyTypeError::new_err(format!(
                "regions[{k}] must be (x, y, z, radius); regions is a file path or a sequence of them"
            ))
        })?;
        balls.push(Ball {
            center: [x, y, z].into(),
            radius: r,
        });
    }
    Ok((balls, None))
}

/// The memory budget: bytes (int) or a size such as "8G", "512M"; None: the CLI's default.
fn max_memory_from(obj: Option<&Bound<'_, PyAny>>) -> PyResult<u64> {
    match obj.filter(|o| !o.is_none()) {
        None => Ok(vesselmsr::budget::default_max_memory()),
        Some(o) if o.is_instance_of::<PyString>() => {
            vesselmsr::budget::max_memory(Some(&o.extract::<String>()?)).map_err(py_error)
        }
        Some(o) => o.extract::<u64>().map_err(|_| {
            PyTypeError::new_err("max_memory must be bytes (int) or a size such as \"8G\"")
        }),
    }
}

/// Repairs a vessel mesh as `vesselmsr repair` does and returns (vertices, faces, report).
///
/// vertices: (n, 3) float64 or float32; faces: (m, 3) integers (vertex indices from 0).
/// holes: every boundary loop that is not an open vessel end is inpainted (--holes).
/// regions: a regions file (JSON, .mrk.json, .fcsv) or a sequence of balls (x, y, z, radius).
/// stenoses: True (20%) or a percentage: narrowings found on the centreline are repaired
/// (None or False: not looked for).
/// units: the name of the coordinates' unit (report and scale check; never rescaled).
/// voxel, method, speed, time, epsilon, max_iterations, keep_outside, open_ends, decimate,
/// max_memory: as the CLI's --voxel, --method, -c, --time, --epsilon, --max-iterations,
/// --no-keep-outside, --open-ends, --decimate (True: 0.5 voxel), --max-memory (bytes or "8G").
///
/// Returns vertices float64 (n', 3), faces int64 (m', 3) and the report as a dict (the CLI's
/// --report JSON without the file paths and the read time). The GIL is released meanwhile.
#[pyfunction]
#[pyo3(signature = (vertices, faces, *, holes=true, regions=None, stenoses=None, units="mm",
    voxel=None, method="centerline", speed=None, time=None, epsilon=None, max_iterations=None,
    keep_outside=true, open_ends=false, decimate=None, max_memory=None))]
#[allow(clippy::too_many_arguments)]
fn repair<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    holes: bool,
    regions: Option<&Bound<'py, PyAny>>,
    stenoses: Option<&Bound<'py, PyAny>>,
    units: &str,
    voxel: Option<f64>,
    method: &str,
    speed: Option<f64>,
    time: Option<f64>,
    epsilon: Option<f64>,
    max_iterations: Option<usize>,
    keep_outside: bool,
    open_ends: bool,
    decimate: Option<&Bound<'py, PyAny>>,
    max_memory: Option<&Bound<'py, PyAny>>,
) -> PyResult<Repaired<'py>> {
    let method: InpaintMethod = method
        .parse()
        .map_err(|e: Error| PyValueError::new_err(e.to_string()))?;
    let (balls, regions_file) = regions_from(regions)?;
    let request = VesselRepair {
        balls,
        regions_file,
        holes,
        stenoses: flag_or_number(stenoses, "stenoses", 20.0)?,
        decimate: flag_or_number(decimate, "decimate", 0.5)?,
        units: units.to_string(),
        options: RepairOptions {
            method,
            voxel,
            keep_outside,
            open_ends,
            speed,
            time,
            epsilon,
            max_iterations: max_iterations.unwrap_or(RepairOptions::default().max_iterations),
            ..RepairOptions::default()
        },
        max_memory: max_memory_from(max_memory)?,
        input_path: None,
        output_path: None,
    };
    request.validate().map_err(py_error)?;
    let mesh = mesh_from(vertices, faces)?;
    let (done, text) = detached(
        py,
        |notices| {
            repair_vessel(&mesh, &request, &mut |event| {
                if let RepairEvent::Notice(text) = event {
                    notices.push(text.to_string());
                }
            })
        },
        |done| serde_json::to_string(&done.report),
    )?;
    let mut later: Vec<String> = done
        .repair_notices
        .iter()
        .map(|n| format!("mesh: {n}"))
        .collect();
    if let Some(why) = &done.report.parameters.fallback {
        later.push(format!(
            "the patch could not be stitched into the kept triangles ({why}); the whole vessel was re-meshed"
        ));
    }
    warn_all(py, &later)?;
    let (v, f) = arrays_of(py, &done.mesh)?;
    Ok((v, f, from_json(py, &text)?))
}

/// Closes every boundary loop as `vesselmsr cap` does and returns (vertices, faces, report).
///
/// vertices: (n, 3) float64 or float32; faces: (m, 3) integers (vertex indices from 0).
/// target_edge: target edge length of the cap triangles, in the mesh's units (None: the mean
/// length of each loop's own edges), as --target-edge.
/// orient: fix triangles wound against their neighbours and face the result outward (the
/// default); False keeps the input's winding (--no-orient).
///
/// Coincident vertices are merged first (a triangle soup becomes the surface it describes). The
/// result is watertight or VesselmsrError is raised. Returns vertices float64 (n', 3), faces
/// int64 (m', 3) and the report as a dict, equal to what `vesselmsr cap --json` prints (input,
/// cap, output, inconsistent_faces_flipped; that JSON has no file path or timing). The notices
/// are VesselmsrWarning warnings. The GIL is released meanwhile.
#[pyfunction]
#[pyo3(signature = (vertices, faces, *, target_edge=None, orient=true))]
fn cap<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    target_edge: Option<f64>,
    orient: bool,
) -> PyResult<Repaired<'py>> {
    let opts = CapOptions {
        target_edge_length: target_edge,
        orient_outward: orient,
        ..CapOptions::default()
    };
    let mesh = mesh_from(vertices, faces)?;
    let (done, text) = detached(
        py,
        |notices| {
            cap_mesh(&mesh, &opts, &mut |merged| {
                notices.push(format!(
                    "{merged} vertices at the same position as another were merged"
                ))
            })
        },
        |done| serde_json::to_string(done),
    )?;
    warn_all(py, &done.notices())?;
    let (v, f) = arrays_of(py, &done.mesh)?;
    Ok((v, f, from_json(py, &text)?))
}

/// Re-meshes through the level set as `vesselmsr remesh` does and returns (vertices, faces,
/// report): the zero level set of the mesh's signed distance grid by marching cubes, projected
/// onto the input; a closed, manifold, outward mesh at the grid's resolution.
///
/// vertices: (n, 3) float64 or float32; faces: (m, 3) integers (vertex indices from 0).
/// voxel: voxel edge length in the mesh's units, or resolution: cells along the longest side of
/// the bounding box (not both; neither: min(mean edge / 2, longest side / 256)), as --voxel and
/// --resolution.
/// project: move the vertices onto the input and split the edges still off it (the default);
/// False keeps the marching-cubes surface (--no-project).
/// decimate: True (0.5 voxel) or a number of voxels: simplify the output within that Hausdorff
/// distance (None or False: not simplified), as --decimate.
/// max_memory: the grid's memory limit, bytes or a size such as "8G" (None: the CLI's default),
/// as --max-memory.
///
/// Returns vertices float64 (n', 3), faces int64 (m', 3) and the report as a dict: what
/// `vesselmsr remesh --json` prints (grid, output, cavities_joined, edges_split, decimate)
/// without its timings. Notices are VesselmsrWarning warnings. The GIL is released meanwhile.
#[pyfunction]
#[pyo3(signature = (vertices, faces, *, voxel=None, resolution=None, project=true,
    decimate=None, max_memory=None))]
fn remesh<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    voxel: Option<f64>,
    resolution: Option<usize>,
    project: bool,
    decimate: Option<&Bound<'py, PyAny>>,
    max_memory: Option<&Bound<'py, PyAny>>,
) -> PyResult<Repaired<'py>> {
    let opts = RemeshOptions {
        grid: GridOptions {
            voxel,
            resolution,
            max_memory_bytes: max_memory_from(max_memory)?,
            ..GridOptions::default()
        },
        project,
        decimate: flag_or_number(decimate, "decimate", 0.5)?,
    };
    opts.validate().map_err(py_error)?;
    let mesh = mesh_from(vertices, faces)?;
    let (done, text) = detached(
        py,
        |notices| {
            remesh_mesh(&mesh, &opts, &mut |event| {
                if let RemeshEvent::Notice(text) = event {
                    notices.push(text.to_string());
                }
            })
        },
        |done| serde_json::to_string(&done.report),
    )?;
    let (v, f) = arrays_of(py, &done.mesh)?;
    Ok((v, f, from_json(py, &text)?))
}

/// Reads a mesh file (.stl, .obj, .ply, .vtp, .vtk) as (vertices float64 (n, 3), faces int64
/// (m, 3)), checked as the CLI checks it.
#[pyfunction]
fn read_mesh<'py>(py: Python<'py>, path: PathBuf) -> PyResult<MeshArrays<'py>> {
    let mesh = py
        .detach(|| vesselmsr::io::read_mesh(&path))
        .map_err(py_error)?;
    arrays_of(py, &mesh)
}

/// Writes a mesh file, the format from the extension (.stl float32, .obj, .ply, .vtp float64,
/// .vtk), atomically.
#[pyfunction]
fn write_mesh(
    py: Python<'_>,
    path: PathBuf,
    vertices: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
) -> PyResult<()> {
    let mesh = mesh_from(vertices, faces)?;
    py.detach(|| vesselmsr::io::write_mesh(&path, &mesh))
        .map_err(py_error)
}

/// The measures of `vesselmsr info --json` as a dict: counts, components, boundary loops,
/// watertight, orientation, volume (None unless watertight), area, bounding box, mean edge,
/// Euler characteristic and genus.
#[pyfunction]
fn mesh_info<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let mesh = mesh_from(vertices, faces)?;
    let text = py
        .detach(|| serde_json::to_string(&vesselmsr::mesh::info::mesh_info(&mesh)))
        .map_err(|e| VesselmsrError::new_err(e.to_string()))?;
    from_json(py, &text)
}

/// Repairs triangulated blood-vessel surfaces (level-set multiscale representation and
/// inpainting) on numpy arrays: repair, cap, remesh, read_mesh, write_mesh, mesh_info.
#[pymodule]
#[pyo3(name = "vesselmsr")]
fn vesselmsr_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("VesselmsrError", py.get_type::<VesselmsrError>())?;
    m.add("VesselmsrWarning", py.get_type::<VesselmsrWarning>())?;
    m.add_function(wrap_pyfunction!(repair, m)?)?;
    m.add_function(wrap_pyfunction!(cap, m)?)?;
    m.add_function(wrap_pyfunction!(remesh, m)?)?;
    m.add_function(wrap_pyfunction!(read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(write_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh_info, m)?)?;
    Ok(())
}
