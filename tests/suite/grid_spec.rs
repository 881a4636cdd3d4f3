//! Sizing a grid for a mesh: the default voxel rule (figures on the six real meshes), the
//! `--voxel` and `--resolution` overrides, padding and centring, the memory estimate against the
//! real allocation, the memory limit and the errors that name the flags.

use crate::common;
use common::*;
use nalgebra::{Point3, Vector3};
use vesselmsr::grid::spec::{
    default_voxel, format_bytes, grid_for_box, grid_memory_bytes, parse_memory_size,
    DEFAULT_MAX_MEMORY_BYTES,
};
use vesselmsr::grid::{grid_for_mesh, Grid3, GridOptions, GridSpec};
use vesselmsr::mesh::measures::{bounding_box, mean_edge_length};
use vesselmsr::mesh::primitives::{icosphere, open_tube};
use vesselmsr::TriMesh;

/// Checks the layout of `spec` around `mesh`: voxel `h`, the fewest cells covering each extent,
/// centred, `pad` nodes beyond on every side.
fn assert_layout(mesh: &TriMesh, spec: &GridSpec, h: f64, pad: usize) {
    let (lo, hi) = bounding_box(mesh);
    assert_eq!(spec.voxel(), h);
    let first = Point3::from(spec.transform.origin);
    let last = first + Vector3::from_fn(|a, _| (spec.dims[a] - 1) as f64 * h);
    for a in 0..3 {
        let cells = spec.dims[a] - 1 - 2 * pad;
        let extent = hi[a] - lo[a];
        assert!(
            cells as f64 * h >= extent * (1.0 - 1e-9),
            "axis {a}: {cells} cells cover {extent}"
        );
        assert!(
            cells == 0 || ((cells - 1) as f64) * h < extent,
            "axis {a}: {cells} cells are the fewest"
        );
        // Margins: pad voxels plus half the slack on both sides.
        let (below, above) = (lo[a] - first[a], last[a] - hi[a]);
        assert!(below >= pad as f64 * h - 1e-9 * h && above >= pad as f64 * h - 1e-9 * h);
        assert!(
            (below - above).abs() < 1e-9 * h.max(extent),
            "axis {a}: centred ({below} vs {above})"
        );
    }
}

#[test]
fn default_rule_on_the_real_meshes() {
    let Some(meshes) = real_meshes() else { return };
    let opts = GridOptions::default();
    println!("mesh | mean edge / 2 | longest / 256 | h | dims | nodes | estimate (3 f32 grids)");
    for (name, mesh) in &meshes {
        let (lo, hi) = bounding_box(mesh);
        let longest = (hi - lo).max();
        let mean = mean_edge_length(mesh);
        let spec = grid_for_mesh(mesh, &opts).unwrap();
        let h = (mean / 2.0).min(longest / 256.0);
        assert_eq!(spec.voxel(), h, "{name}");
        assert_eq!(default_voxel(mean, longest), h);
        assert_layout(mesh, &spec, h, opts.padding_voxels);
        let longest_cells = (0..3)
            .map(|a| spec.dims[a] - 1 - 2 * opts.padding_voxels)
            .max()
            .unwrap();
        assert!(
            longest_cells >= 256,
            "{name}: at least 256 cells on the longest side"
        );
        assert_eq!(spec.estimated_bytes, grid_memory_bytes(spec.dims, 3));
        println!(
            "{name} | {:.4e} | {:.4e} | {h:.4e} | {:?} | {} | {}",
            mean / 2.0,
            longest / 256.0,
            spec.dims,
            spec.node_count(),
            format_bytes(spec.estimated_bytes)
        );
    }
}

#[test]
fn resolution_puts_exactly_n_cells_on_the_longest_side() {
    let mesh = open_tube(1.3, 7.1, 24, 9);
    let (lo, hi) = bounding_box(&mesh);
    let longest = (hi - lo).max();
    for n in [1, 3, 7, 10, 49, 100, 256, 333, 1000] {
        for pad in [0, 2] {
            let opts = GridOptions {
                resolution: Some(n),
                padding_voxels: pad,
                ..Default::default()
            };
            let spec = grid_for_mesh(&mesh, &opts).unwrap();
            assert_eq!(spec.voxel(), longest / n as f64);
            let cells = spec.dims.iter().max().unwrap() - 1 - 2 * pad;
            assert_eq!(cells, n, "resolution {n}");
            assert_layout(&mesh, &spec, longest / n as f64, pad);
        }
    }
}

#[test]
fn voxel_sets_the_voxel_size() {
    let mesh = icosphere(3, 2.0, Point3::new(100.0, -50.0, 3.0));
    for h in [0.05, 0.3, 1.0, 3.9, 4.0] {
        let opts = GridOptions {
            voxel: Some(h),
            ..Default::default()
        };
        let spec = grid_for_mesh(&mesh, &opts).unwrap();
        assert_layout(&mesh, &spec, h, 4);
    }
}

#[test]
fn bad_requests_are_errors_that_name_the_flag() {
    let mesh = icosphere(2, 1.0, Point3::origin());
    let longest = {
        let (lo, hi) = bounding_box(&mesh);
        (hi - lo).max()
    };
    let err = |opts: GridOptions| grid_for_mesh(&mesh, &opts).unwrap_err().to_string();
    for v in [0.0, -1.0, f64::NAN, f64::INFINITY, longest * 1.001] {
        let e = err(GridOptions {
            voxel: Some(v),
            ..Default::default()
        });
        println!("--voxel {v}: {e}");
        assert!(e.contains("--voxel"), "{e}");
    }
    let e = err(GridOptions {
        resolution: Some(0),
        ..Default::default()
    });
    assert!(e.contains("--resolution"), "{e}");
    let e = err(GridOptions {
        voxel: Some(0.1),
        resolution: Some(10),
        ..Default::default()
    });
    assert!(e.contains("--voxel") && e.contains("--resolution"), "{e}");
    let e = err(GridOptions {
        grids: 0,
        ..Default::default()
    });
    assert!(e.contains("grid"), "{e}");
    assert!(grid_for_mesh(&TriMesh::new(vec![], vec![]), &GridOptions::default()).is_err());
    let flat = TriMesh::new(vec![Point3::new(1.0, 2.0, 3.0); 3], vec![[0, 1, 2]]);
    assert!(
        grid_for_mesh(&flat, &GridOptions::default()).is_err(),
        "a mesh with no extent"
    );
}

#[test]
fn memory_limit_refuses_with_the_flags_named() {
    let mesh = icosphere(2, 1.0, Point3::origin());
    // Enormous requests are refused, not overflowed.
    for n in [100_000, 10_000_000, usize::MAX] {
        let e = grid_for_mesh(
            &mesh,
            &GridOptions {
                resolution: Some(n),
                ..Default::default()
            },
        )
        .unwrap_err()
        .to_string();
        if n == 100_000 {
            println!("{e}");
        }
        for flag in ["--voxel", "--resolution", "--max-memory"] {
            assert!(e.contains(flag), "{e}");
        }
        assert!(e.contains("8.0 GiB"), "{e}");
    }
    let e = grid_for_mesh(
        &mesh,
        &GridOptions {
            voxel: Some(1e-300),
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("--max-memory"), "{e}");
    // The limit is inclusive: exactly the estimate passes, one byte less does not.
    let opts = GridOptions {
        resolution: Some(64),
        ..Default::default()
    };
    let spec = grid_for_mesh(&mesh, &opts).unwrap();
    let at = GridOptions {
        max_memory_bytes: spec.estimated_bytes,
        ..opts
    };
    assert_eq!(grid_for_mesh(&mesh, &at).unwrap(), spec);
    let below = GridOptions {
        max_memory_bytes: spec.estimated_bytes - 1,
        ..opts
    };
    assert!(grid_for_mesh(&mesh, &below).is_err());
    // The estimate scales with the number of grids held.
    let one = GridOptions { grids: 1, ..opts };
    let spec1 = grid_for_mesh(&mesh, &one).unwrap();
    assert_eq!(spec1.dims, spec.dims);
    assert_eq!(spec.estimated_bytes, 3 * spec1.estimated_bytes);
    assert_eq!(GridOptions::default().max_memory_bytes, 8 << 30);
    assert_eq!(DEFAULT_MAX_MEMORY_BYTES, 8 * 1024 * 1024 * 1024);
}

#[test]
fn estimate_equals_the_allocation_of_one_grid() {
    let mesh = open_tube(0.7, 5.0, 16, 6);
    let opts = GridOptions {
        grids: 1,
        resolution: Some(90),
        ..Default::default()
    };
    let spec = grid_for_mesh(&mesh, &opts).unwrap();
    let grid = spec.new_grid(1.0).unwrap();
    assert_eq!(grid.dims(), spec.dims);
    assert_eq!(grid.transform(), &spec.transform);
    let len = grid.data().len();
    assert_eq!(len, spec.node_count());
    let vec = grid.into_data();
    assert_eq!(
        vec.capacity(),
        len,
        "Grid3::new allocates exactly the nodes"
    );
    let real = vec.capacity() * std::mem::size_of::<f32>() + std::mem::size_of::<Grid3>();
    println!(
        "grid {:?}: estimate {} B, allocated {} B of values + {} B of struct",
        spec.dims,
        spec.estimated_bytes,
        vec.capacity() * 4,
        std::mem::size_of::<Grid3>()
    );
    assert_eq!(spec.estimated_bytes, real as u64);
}

#[test]
fn grid_for_box_matches_grid_for_mesh() {
    let mesh = icosphere(2, 3.0, Point3::new(1.0, 2.0, 3.0));
    let (lo, hi) = bounding_box(&mesh);
    let opts = GridOptions::default();
    assert_eq!(
        grid_for_box(&lo, &hi, mean_edge_length(&mesh), &opts).unwrap(),
        grid_for_mesh(&mesh, &opts).unwrap()
    );
}

#[test]
fn memory_sizes_parse() {
    for (text, want) in [
        ("8G", 8u64 << 30),
        ("8GiB", 8 << 30),
        ("8 gb", 8 << 30),
        ("512M", 512 << 20),
        ("512MiB", 512 << 20),
        ("1.5g", 3 << 29),
        ("100000", 100_000),
        ("64k", 65_536),
        ("2T", 2 << 40),
        (" 3G ", 3 << 30),
    ] {
        assert_eq!(parse_memory_size(text).unwrap(), want, "{text}");
    }
    for text in ["", "G", "abc", "-1", "8X", "8 GiBs", "0", "1.2.3G", "1e30T"] {
        let e = parse_memory_size(text).unwrap_err().to_string();
        assert!(e.contains("--max-memory"), "{text}: {e}");
    }
    assert_eq!(format_bytes(8 << 30), "8.0 GiB");
    assert_eq!(format_bytes(1536), "1.5 KiB");
    assert_eq!(format_bytes(100), "100 B");
}

#[test]
fn a_flat_mesh_gets_one_node_layer_plus_padding() {
    let square = TriMesh::new(
        vec![
            Point3::new(0.0, 0.0, 2.0),
            Point3::new(3.0, 0.0, 2.0),
            Point3::new(3.0, 1.5, 2.0),
            Point3::new(0.0, 1.5, 2.0),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    );
    let spec = grid_for_mesh(
        &square,
        &GridOptions {
            resolution: Some(12),
            padding_voxels: 2,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(spec.dims, [12 + 1 + 4, 6 + 1 + 4, 1 + 4]);
    assert_layout(&square, &spec, 0.25, 2);
    assert_eq!(spec.transform.origin[2], 2.0 - 2.0 * 0.25);
}
