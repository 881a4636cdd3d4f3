//! Padding, sub-boxes and subsampling of a Grid3: world positions and values kept, extract /
//! write-back round trips, the SubBox helpers against brute force, and the errors.

use crate::common;
use common::*;
use nalgebra::{Point3, Vector3};
use rand::RngExt;
use vesselmsr::grid::{Grid3, GridTransform, SubBox};

fn random_grid(dims: [usize; 3], seed: u64) -> Grid3 {
    let mut rng = rng(seed);
    let t = GridTransform::new(Point3::new(-3.25, 1.5, 10.0), 0.125);
    let mut g = Grid3::new(dims, t, 0.0).unwrap();
    g.data_mut()
        .iter_mut()
        .for_each(|v| *v = rng.random::<f32>() * 2.0 - 1.0);
    g
}

#[test]
fn pad_keeps_every_node_in_place_and_fills_the_rim() {
    let g = random_grid([5, 4, 3], 1);
    for n in [0, 1, 3] {
        let p = g.pad(n, 7.5).unwrap();
        assert_eq!(p.dims(), [5 + 2 * n, 4 + 2 * n, 3 + 2 * n]);
        assert_eq!(p.voxel(), g.voxel());
        let shift = Vector3::from_element(n as f64 * g.voxel());
        assert!(
            (Point3::from(p.transform().origin) + shift - Point3::from(g.transform().origin))
                .norm()
                < 1e-12
        );
        let mut fills = 0;
        for k in 0..p.dims()[2] {
            for j in 0..p.dims()[1] {
                for i in 0..p.dims()[0] {
                    let inner = [i, j, k]
                        .iter()
                        .zip(g.dims())
                        .all(|(&c, d)| c >= n && c < n + d);
                    if inner {
                        assert_eq!(p.get(i, j, k), g.get(i - n, j - n, k - n));
                        assert!((p.world(i, j, k) - g.world(i - n, j - n, k - n)).norm() < 1e-12);
                    } else {
                        assert_eq!(p.get(i, j, k), 7.5);
                        fills += 1;
                    }
                }
            }
        }
        assert_eq!(fills, p.data().len() - g.data().len());
        // Sampling inside the old grid is unchanged (the interpolants only see the old nodes).
        let mut rng = rng(2);
        for _ in 0..200 {
            let u = Vector3::from_fn(|a, _| rng.random::<f64>() * (g.dims()[a] - 1) as f64);
            let q = g.transform().index_to_world(u);
            let (a, b) = (
                g.sample_trilinear(&q).unwrap(),
                p.sample_trilinear(&q).unwrap(),
            );
            assert!((a - b).abs() < 1e-12, "trilinear at {q}: {a} vs {b}");
        }
    }
    assert_eq!(g.pad(0, 1.0).unwrap(), g);
    assert!(
        g.pad(usize::MAX / 2, 0.0).is_err(),
        "overflowing padding is an error"
    );
}

#[test]
fn subsample_keeps_every_strided_node_where_it_was() {
    let g = random_grid([9, 8, 5], 11);
    for stride in 1..=4 {
        let s = g.subsample(stride).unwrap();
        // (n − 1)/stride + 1 nodes: the last one at or before the parent's last.
        let want = [9, 8, 5].map(|n: usize| (n - 1) / stride + 1);
        assert_eq!(s.dims(), want, "stride {stride}");
        assert!((s.voxel() - g.voxel() * stride as f64).abs() < 1e-15);
        let mut seen = 0;
        for [i, j, k] in s.whole_box().nodes() {
            let (pi, pj, pk) = (i * stride, j * stride, k * stride);
            assert_eq!(
                s.get(i, j, k),
                g.get(pi, pj, pk),
                "stride {stride} node {i},{j},{k}"
            );
            assert!((s.world(i, j, k) - g.world(pi, pj, pk)).norm() < 1e-12);
            seen += 1;
        }
        assert_eq!(seen, want.iter().product::<usize>());
    }
    assert_eq!(g.subsample(1).unwrap(), g);
    // A grid of one node per axis stays one node; a stride past the grid keeps node 0 only.
    let one = g.subsample(100).unwrap();
    assert_eq!(one.dims(), [1, 1, 1]);
    assert_eq!(one.get(0, 0, 0), g.get(0, 0, 0));
    assert!(g.subsample(0).is_err());
}

#[test]
fn extract_then_write_back_round_trips() {
    let mut g = random_grid([9, 7, 6], 3);
    let original = g.clone();
    let b = SubBox::new([2, 1, 3], [7, 5, 6]);
    let sub = g.extract(&b).unwrap();
    assert_eq!(sub.dims(), [5, 4, 3]);
    assert_eq!(sub.voxel(), g.voxel());
    for [i, j, k] in SubBox::whole(sub.dims()).nodes() {
        let (pi, pj, pk) = (i + 2, j + 1, k + 3);
        assert_eq!(sub.get(i, j, k), g.get(pi, pj, pk));
        assert!((sub.world(i, j, k) - g.world(pi, pj, pk)).norm() < 1e-12);
    }
    // The sub-grid samples like its parent where both have the nodes.
    let mut rng = rng(4);
    for _ in 0..300 {
        let u = Vector3::from_fn(|a, _| rng.random::<f64>() * (sub.dims()[a] - 1) as f64);
        let q = sub.transform().index_to_world(u);
        assert!(
            (sub.sample_trilinear(&q).unwrap() - g.sample_trilinear(&q).unwrap()).abs() < 1e-12
        );
    }
    // Unchanged write-back is the identity; a changed one touches exactly the box.
    g.write_back(&b, &sub).unwrap();
    assert_eq!(g, original);
    let mut changed = sub.clone();
    changed.data_mut().iter_mut().for_each(|v| *v += 10.0);
    g.write_back(&b, &changed).unwrap();
    for [i, j, k] in g.whole_box().nodes() {
        let before = original.get(i, j, k);
        let want = if b.contains([i, j, k]) {
            before + 10.0
        } else {
            before
        };
        assert_eq!(g.get(i, j, k), want, "node {i},{j},{k}");
    }
    // The whole box extracts the grid itself.
    assert_eq!(original.extract(&original.whole_box()).unwrap(), original);
}

#[test]
fn bad_boxes_are_errors() {
    let mut g = random_grid([4, 4, 4], 5);
    for b in [
        SubBox::new([0, 0, 0], [5, 4, 4]),
        SubBox::new([1, 1, 1], [1, 3, 3]),
        SubBox::new([3, 0, 0], [2, 4, 4]),
    ] {
        assert!(g.extract(&b).is_err(), "{b:?}");
        let sub = Grid3::new([1, 1, 1], *g.transform(), 0.0).unwrap();
        assert!(g.write_back(&b, &sub).is_err(), "{b:?}");
    }
    let b = SubBox::new([0, 0, 0], [2, 2, 2]);
    let wrong = Grid3::new([2, 2, 3], *g.transform(), 0.0).unwrap();
    let err = g.write_back(&b, &wrong).unwrap_err().to_string();
    assert!(err.contains("[2, 2, 3]"), "{err}");
}

#[test]
fn sub_box_helpers_match_brute_force() {
    let dims = [6, 5, 4];
    let b = SubBox::new([1, 2, 0], [4, 5, 3]);
    assert_eq!(b.dims(), [3, 3, 3]);
    assert_eq!(b.node_count(), 27);
    assert!(!b.is_empty() && b.fits(dims) && !b.fits([3, 5, 4]));
    assert!(SubBox::new([2, 0, 0], [2, 1, 1]).is_empty());
    assert_eq!(SubBox::new([3, 0, 0], [2, 1, 1]).dims(), [0, 1, 1]);
    assert_eq!(SubBox::new([3, 0, 0], [2, 1, 1]).nodes().count(), 0);
    assert_eq!(b.dilate(2, dims), SubBox::new([0, 0, 0], [6, 5, 4]));
    assert_eq!(b.dilate(1, dims), SubBox::new([0, 1, 0], [5, 5, 4]));
    assert_eq!(
        b.intersection(&SubBox::new([3, 0, 2], [9, 9, 9])),
        SubBox::new([3, 2, 2], [4, 5, 3])
    );
    // nodes(): the box's nodes, each once, x fastest; rows(): the same nodes as flat indices.
    let g = Grid3::new(dims, GridTransform::new(Point3::origin(), 1.0), 0.0).unwrap();
    let listed: Vec<[usize; 3]> = b.nodes().collect();
    let mut brute = Vec::new();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                if b.contains([i, j, k]) {
                    brute.push([i, j, k]);
                }
            }
        }
    }
    assert_eq!(listed, brute);
    let flat: Vec<usize> = b.rows(dims).flat_map(|(_, _, r)| r).collect();
    let want: Vec<usize> = brute.iter().map(|&[i, j, k]| g.index(i, j, k)).collect();
    assert_eq!(flat, want);
    for (j, k, r) in b.rows(dims) {
        assert_eq!(g.coords(r.start), [b.min[0], j, k]);
    }
    let whole: Vec<usize> = g
        .whole_box()
        .nodes()
        .map(|[i, j, k]| g.index(i, j, k))
        .collect();
    assert_eq!(whole, (0..g.data().len()).collect::<Vec<_>>());
}

#[test]
fn around_world_holds_exactly_the_nodes_in_the_world_box() {
    let dims = [12, 9, 7];
    let t = GridTransform::new(Point3::new(-1.0, 2.0, 0.5), 0.3);
    let g = Grid3::new(dims, t, 0.0).unwrap();
    let mut rng = rng(6);
    for trial in 0..300 {
        // Boxes partly or wholly outside the grid, some with corners exactly on nodes.
        let mut a = Point3::from(Vector3::from_fn(|_, _| rng.random::<f64>() * 6.0 - 2.0))
            + Vector3::new(-1.0, 2.0, 0.5);
        let mut b = a + Vector3::from_fn(|_, _| rng.random::<f64>() * 2.5);
        if trial % 5 == 0 {
            a = g.world(3, 2, 1);
            b = g.world(7, 5, 4);
        }
        if trial % 7 == 0 {
            std::mem::swap(&mut a, &mut b);
        }
        let sb = SubBox::around_world(&a, &b, &t, dims);
        for [i, j, k] in g.whole_box().nodes() {
            let p = g.world(i, j, k);
            let inside = (0..3).all(|x| a[x] <= p[x] && p[x] <= b[x]);
            assert_eq!(
                sb.contains([i, j, k]),
                inside,
                "trial {trial}: node {i},{j},{k} box {a} .. {b}"
            );
        }
        assert!(sb.is_empty() || sb.fits(dims));
        if trial % 5 == 0 && trial % 7 != 0 {
            assert_eq!(sb, SubBox::new([3, 2, 1], [8, 6, 5]));
        }
    }
    let nan = Point3::new(f64::NAN, 0.0, 0.0);
    assert!(SubBox::around_world(&nan, &Point3::new(9.0, 9.0, 9.0), &t, dims).is_empty());
}
