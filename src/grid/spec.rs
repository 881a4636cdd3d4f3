//! Sizing a grid for a mesh: the voxel size (a default rule, or `--voxel` / `--resolution`), the
//! padding around the mesh's bounding box, and an up-front memory estimate checked against a
//! limit (`--max-memory`, default 8 GiB) before anything is allocated.
//!
//! **Default voxel size:** `h = min(mean edge / 2, longest extent / 256)`, in the mesh's units.
//! The first term puts two voxels on every mean triangle edge, so the grid resolves the features
//! the mesh itself resolves (the Nyquist-like rule of the issue); the second guarantees at least
//! 256 cells along the longest side, so a coarsely triangulated mesh still gets a usable grid.
//! Both are relative to the mesh, so the rule does not depend on its units. Being a minimum, the
//! rule is a floor on resolution, not a cap: a long, finely triangulated mesh can ask for more
//! than 256 cells per side, and the memory limit is what stops a grid that would not fit.
//!
//! **Layout:** the cells along each axis are the fewest that cover the bounding box (`⌈extent/h⌉`),
//! centred on it, plus `padding_voxels` nodes on every side; node (0, 0, 0) is the origin. The
//! grid has `cells + 1 + 2·padding` nodes per axis.
//!
//! **Memory estimate:** `grids × (4 bytes × nodes + size_of::<Grid3>())`, `grids` being the number
//! of f32 grids of these dimensions the caller will hold at once ([`GridOptions::grids`], default
//! 3: φ, a scratch copy and a sweep buffer). One grid's estimate is exactly what [`Grid3::new`]
//! allocates; what else a pipeline holds (mesh, BVH, band lists) is not counted.

use super::{Grid3, GridTransform};
use crate::mesh::measures::{bounding_box, mean_edge_length};
use crate::{Error, Result, TriMesh};
use nalgebra::Point3;

/// Default memory limit: 8 GiB.
pub const DEFAULT_MAX_MEMORY_BYTES: u64 = 8 << 30;

/// Largest coordinate a grid is sized for: φ is float32 (largest 3.4e38), and distances and
/// their squares must stay finite in the level-set steps.
pub const MAX_COORDINATE: f64 = 1e18;

/// Cells along the longest axis below which the default voxel size never goes.
pub const DEFAULT_MIN_CELLS: usize = 256;

/// How a grid is sized for a mesh. `voxel` and `resolution` are alternatives (at most one).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridOptions {
    /// Voxel edge length in world (file) units; None for the default rule.
    pub voxel: Option<f64>,
    /// Cells along the longest axis of the mesh's bounding box; None for the default rule.
    pub resolution: Option<usize>,
    /// Nodes added around the bounding box on every side, in voxels (default 4: a ±3h narrow
    /// band plus one node, so the zero level set never reaches the border).
    pub padding_voxels: usize,
    /// Largest memory estimate accepted, bytes (default 8 GiB).
    pub max_memory_bytes: u64,
    /// Number of f32 grids of these dimensions held at once, for the estimate (default 3).
    pub grids: usize,
}

impl Default for GridOptions {
    fn default() -> Self {
        GridOptions {
            voxel: None,
            resolution: None,
            padding_voxels: 4,
            max_memory_bytes: DEFAULT_MAX_MEMORY_BYTES,
            grids: 3,
        }
    }
}

/// A sized grid: its dimensions, transform and memory estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridSpec {
    /// Nodes along x, y, z.
    pub dims: [usize; 3],
    /// Origin (node (0, 0, 0)) and voxel size, world units.
    pub transform: GridTransform,
    /// Estimated bytes for [`GridOptions::grids`] grids of these dimensions.
    pub estimated_bytes: u64,
}

impl GridSpec {
    /// Voxel edge length, world units.
    pub fn voxel(&self) -> f64 {
        self.transform.voxel
    }

    /// Number of nodes of one grid.
    pub fn node_count(&self) -> usize {
        self.dims.iter().product()
    }

    /// Allocates one grid of this spec filled with `fill`.
    pub fn new_grid(&self, fill: f32) -> Result<Grid3> {
        Grid3::new(self.dims, self.transform, fill)
    }
}

/// The grid layout as the JSON outputs print it (the CLI's level-set commands, the Python
/// package's `remesh`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct GridJson {
    pub dims: [usize; 3],
    pub voxel: f64,
    pub origin: [f64; 3],
}

impl GridJson {
    pub fn of(spec: &GridSpec) -> Self {
        GridJson {
            dims: spec.dims,
            voxel: spec.transform.voxel,
            origin: spec.transform.origin,
        }
    }
}

/// Bytes held by `grids` f32 grids of `dims` nodes: `grids × (4·nodes + size_of::<Grid3>())`,
/// saturating at `u64::MAX`.
pub fn grid_memory_bytes(dims: [usize; 3], grids: usize) -> u64 {
    let nodes = dims.iter().map(|&d| d as u128).product::<u128>();
    let one = nodes * 4 + std::mem::size_of::<Grid3>() as u128;
    u64::try_from(one * grids as u128).unwrap_or(u64::MAX)
}

/// The default voxel size of a mesh with this mean edge length and longest bounding-box extent:
/// `min(mean_edge / 2, longest / 256)` (the second term alone when the first is not positive).
pub fn default_voxel(mean_edge: f64, longest_extent: f64) -> f64 {
    let cap = longest_extent / DEFAULT_MIN_CELLS as f64;
    let resolve = mean_edge / 2.0;
    if resolve > 0.0 && resolve.is_finite() {
        resolve.min(cap)
    } else {
        cap
    }
}

/// Sizes a grid around `mesh` (see the module documentation for the rule, layout and estimate).
///
/// Errors, naming the flags: `voxel` and `resolution` both given; a voxel that is not positive
/// and finite or larger than the mesh's longest extent; a resolution of 0; `grids` of 0; an empty
/// mesh; and a memory estimate above `max_memory_bytes`.
pub fn grid_for_mesh(mesh: &TriMesh, opts: &GridOptions) -> Result<GridSpec> {
    if mesh.vertices.is_empty() {
        return Err(Error::Geometry(
            "cannot size a grid for a mesh without vertices".into(),
        ));
    }
    let (lo, hi) = bounding_box(mesh);
    // The mean edge only matters for the default rule; skip its cost otherwise.
    let mean_edge = if opts.voxel.is_none() && opts.resolution.is_none() {
        mean_edge_length(mesh)
    } else {
        0.0
    };
    grid_for_box(&lo, &hi, mean_edge, opts)
}

/// Sizes a grid around the world box `[lo, hi]` of a mesh whose mean edge length is `mean_edge`
/// (used only by the default rule); see [`grid_for_mesh`].
pub fn grid_for_box(
    lo: &Point3<f64>,
    hi: &Point3<f64>,
    mean_edge: f64,
    opts: &GridOptions,
) -> Result<GridSpec> {
    let extent = hi - lo;
    let longest = extent.max();
    if !(longest > 0.0 && longest.is_finite() && extent.min() >= 0.0) {
        return Err(Error::Geometry(format!(
            "cannot size a grid for a mesh whose bounding box is {lo} .. {hi}"
        )));
    }
    let farthest = lo.coords.abs().max().max(hi.coords.abs().max());
    if farthest > MAX_COORDINATE {
        return Err(Error::Geometry(format!(
            "coordinates up to {farthest:e} are beyond what a float32 grid holds (±{MAX_COORDINATE:e}): \
             rescale the mesh"
        )));
    }
    if opts.grids == 0 {
        return Err(Error::Geometry(
            "the memory estimate needs at least one grid".into(),
        ));
    }
    let h = match (opts.voxel, opts.resolution) {
        (Some(_), Some(_)) => {
            return Err(Error::Geometry(
                "give --voxel or --resolution, not both".into(),
            ))
        }
        (Some(v), None) => {
            if !(v > 0.0 && v.is_finite()) {
                return Err(Error::Geometry(format!(
                    "--voxel must be a positive length in the mesh's units, got {v}"
                )));
            }
            if v > longest {
                return Err(Error::Geometry(format!(
                    "--voxel {v} is larger than the mesh, whose longest side is {longest} \
                     (in the mesh's units)"
                )));
            }
            v
        }
        (None, Some(0)) => {
            return Err(Error::Geometry(
                "--resolution must be at least 1 cell along the longest side".into(),
            ))
        }
        (None, Some(n)) => longest / n as f64,
        (None, None) => default_voxel(mean_edge, longest),
    };
    let pad = opts.padding_voxels as f64;
    let mut cells = [0.0f64; 3];
    let mut nodes = [0.0f64; 3];
    for a in 0..3 {
        // Fewest cells covering the extent; the slack absorbs round-off of extent / (extent / n).
        cells[a] = (extent[a] / h - 1e-6).ceil().max(0.0);
        nodes[a] = cells[a] + 1.0 + 2.0 * pad;
    }
    let node_count = nodes[0] * nodes[1] * nodes[2];
    let bytes = opts.grids as f64 * (4.0 * node_count + std::mem::size_of::<Grid3>() as f64);
    if bytes > opts.max_memory_bytes as f64 || nodes.iter().any(|&n| n > usize::MAX as f64) {
        return Err(Error::Geometry(format!(
            "a grid of {}×{}×{} nodes (voxel {h}) needs about {} for {} f32 grid{}, more than the \
             {} limit: use a coarser --voxel, a smaller --resolution, or raise --max-memory",
            nodes[0],
            nodes[1],
            nodes[2],
            format_bytes_f64(bytes),
            opts.grids,
            if opts.grids == 1 { "" } else { "s" },
            format_bytes(opts.max_memory_bytes)
        )));
    }
    let dims = nodes.map(|n| n as usize);
    let origin = Point3::from(std::array::from_fn::<f64, 3, _>(|a| {
        lo[a] - pad * h - 0.5 * (cells[a] * h - extent[a])
    }));
    Ok(GridSpec {
        dims,
        transform: GridTransform::new(origin, h),
        estimated_bytes: grid_memory_bytes(dims, opts.grids),
    })
}

/// Parses a memory size: a number of bytes, optionally with a binary suffix K, M, G or T (also
/// written KiB/KB, …; any case; all mean powers of 1024), e.g. `8G`, `512MiB`, `1.5g`, `100000`.
pub fn parse_memory_size(text: &str) -> Result<u64> {
    let t = text.trim();
    let bad = || {
        Error::Geometry(format!(
            "--max-memory: cannot read '{text}' as a size (e.g. 8G, 512M, 100000)"
        ))
    };
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let value: f64 = number.parse().map_err(|_| bad())?;
    let unit = unit.trim().to_ascii_lowercase();
    let unit = unit
        .strip_suffix("ib")
        .or_else(|| unit.strip_suffix('b'))
        .unwrap_or(&unit);
    let scale = match unit {
        "" => 1u64,
        "k" => 1 << 10,
        "m" => 1 << 20,
        "g" => 1 << 30,
        "t" => 1 << 40,
        _ => return Err(bad()),
    };
    let bytes = value * scale as f64;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(bad());
    }
    Ok(bytes.round() as u64)
}

/// A byte count in binary units with one decimal, e.g. "8.0 GiB", "512.0 MiB", "100 B".
pub fn format_bytes(bytes: u64) -> String {
    format_bytes_f64(bytes as f64)
}

fn format_bytes_f64(bytes: f64) -> String {
    const UNITS: [&str; 6] = ["KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    if bytes < 1024.0 {
        return format!("{bytes} B");
    }
    let mut value = bytes / 1024.0;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    format!("{value:.1} {}", UNITS[unit])
}
