//! Samples added where the level-set reconstruction would misread a level (the paper's "denser
//! samples where needed", Algorithm 1, checked against the reconstruction of Section 2). The
//! decomposition knows both φ_{i−1} and φ_i, so it can ask, node by node near S_{i−1}, what the
//! tangent-plane rebuild ([`super::reconstruct::TangentPlanes::node_value`]) will give from φ_i
//! and the samples of S_{i−1}. Where the cortex folds more tightly than the grid (sub-voxel
//! pockets of S_{i−1} that S_i has smoothed over), the samples placed a quarter voxel apart on
//! the marching-cubes surface ([`super::cover`]) can still leave a node reading the wrong side or
//! a distance off by a third of a voxel; a sample at that node's foot point on S_{i−1} (its
//! Newton projection) gives the rebuild the plane it lacked.
//!
//! A node can also be read closely enough and still change S̃_{i−1}: on a grid face whose
//! corners alternate in sign, the marching cubes join the inside corners or not by the sign of
//! the bilinear saddle (the asymptotic decider), and where S_{i−1} pinches that sign turns on
//! errors of hundredths of a voxel, and the two ways differ by up to half a voxel. Such a face,
//! read otherwise than φ_{i−1} decides it, counts its four corners as misread. Their values
//! are near enough for their own check, so their foot points would give the rebuild nothing
//! new; what it lacks is the values themselves, which in a pinch are not the distances to the
//! tricubic surface the samples lie on (the grid's φ_{i−1} there is no distance: |∇φ| falls
//! to a half). So each corner x gets a sample where its own value puts S_{i−1}: at
//! x − φ_{i−1}(x) n(x), with the normal n(x) of x, whose tangent plane gives x exactly
//! φ_{i−1}(x): its normal line passes through x, so the rebuild takes it as x's foot point and
//! gives x that distance alone, not averaged with its neighbours' planes. Such a sample
//! lies off the tricubic zero level set by about what φ_{i−1} there is off a distance (a tenth
//! of a voxel); its detail W_i is still its projection onto S_i.

use super::decompose::{outward_normal, unit_normal};
use super::project::{project_to_zero_level, LevelProjectOptions};
use super::reconstruct::{AdvectOptions, TangentPlanes};
use crate::grid::{face_neighbours, Grid3};
use crate::levelset::speck::{clear_specks, SPECK};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// A node counts as misread when the rebuild's value differs from φ_{i−1} by more than this
/// (voxels), or has the other sign where |φ_{i−1}| exceeds `SIGN_MARGIN` or the node has no
/// neighbour across S_{i−1}.
pub const MISREAD_TOLERANCE: f64 = 0.3;

/// Nodes this near S_{i−1} (voxels), with a neighbour across it, may have either sign in the
/// rebuild (without one, they are the specks the rebuild clears).
const SIGN_MARGIN: f64 = SPECK;

/// A node the rebuild misreads and the sample added for it.
#[derive(Debug, Clone, Copy)]
pub struct Misread {
    /// Index of the node in the grid.
    pub node: usize,
    /// The sample for it on S_{i−1}.
    pub point: Point3<f64>,
    /// The sample's outward unit normal n_{i−1}.
    pub normal: Vector3<f64>,
}

/// The nodes within one voxel of S_{i−1} (|φ_{i−1}| < h) that the rebuild of φ_{i−1} from
/// `phi` (φ_i) and the samples of S_{i−1} (`previous`, with `normals` n_{i−1} and `details`
/// W_i) misreads — a node's value, or a face's decider (see the module doc) — with the samples
/// for them: a misread value's foot point on S_{i−1} (the nodes whose projection converges), a
/// misread face's corner where its value puts S_{i−1}. With `around` (sorted: the nodes
/// found in earlier rounds, whose samples have since been added), only the nodes within two
/// voxels of those are checked, and those themselves are not given again.
#[allow(clippy::too_many_arguments)]
pub fn misread_points(
    previous_phi: &Grid3,
    phi: &Grid3,
    previous: &[Point3<f64>],
    normals: &[Vector3<f64>],
    details: &[Vector3<f64>],
    around: Option<&[usize]>,
    advect: &AdvectOptions,
    projection: &LevelProjectOptions,
) -> Vec<Misread> {
    let h = phi.voxel();
    let truth = previous_phi.data();
    let near = |n: &usize| (truth[*n].abs() as f64) < h;
    let checked: Vec<usize> = match around {
        None => (0..truth.len()).into_par_iter().filter(near).collect(),
        Some(nodes) => {
            let mut candidates = nodes_near(phi, nodes, 2);
            candidates.sort_unstable();
            candidates.dedup();
            candidates.into_iter().filter(near).collect()
        }
    };
    let planes = TangentPlanes::new(phi, previous, normals, details, advect);
    let read: Vec<f32> = checked
        .par_iter()
        .map(|&n| planes.node_value(phi, n))
        .collect();
    // The rebuild's reading at the checked nodes, φ_{i−1} elsewhere (a node farther than h
    // from S_{i−1} read with the other sign is caught by its own check), specks cleared as the
    // rebuild clears them.
    let mut reading = previous_phi.clone();
    for (&n, &b) in checked.iter().zip(&read) {
        reading.data_mut()[n] = b;
    }
    clear_specks(&mut reading, SPECK);
    let values = reading.data();
    let dims = phi.dims();
    let steps = [1, dims[0], dims[0] * dims[1]];
    // (node, whether its own value is misread): a node of a misread face only is read closely
    // enough on its own.
    let mut nodes: Vec<(usize, bool)> = checked
        .par_iter()
        .flat_map_iter(|&n| {
            let (a, b) = (truth[n] as f64, values[n] as f64);
            // Either sign is fine next to S_{i−1} only: a node near zero whose neighbours all
            // share its sign would, flipped, stand alone as a speck of surface.
            let flipped = (a < 0.0) != (b < 0.0)
                && (a.abs() > SIGN_MARGIN * h
                    || face_neighbours(dims, n).all(|m| (truth[m] < 0.0) == (a < 0.0)));
            let misread = (a - b).abs() > MISREAD_TOLERANCE * h || flipped;
            // The three faces with n as their lowest corner, corners in cyclic order.
            let c = phi.coords(n);
            let faces = [(0, 1), (0, 2), (1, 2)]
                .into_iter()
                .filter_map(move |(u, v)| {
                    if c[u] + 1 >= dims[u] || c[v] + 1 >= dims[v] {
                        return None;
                    }
                    let corners = [n, n + steps[u], n + steps[u] + steps[v], n + steps[v]];
                    let decide = |g: &[f32]| face_joined(corners.map(|m| g[m]));
                    (decide(truth) != decide(values)).then_some(corners.map(|m| (m, false)))
                });
            misread
                .then_some((n, true))
                .into_iter()
                .chain(faces.flatten())
        })
        .collect();
    // Value-misread first among a node's entries, then one entry per node.
    nodes.sort_unstable_by_key(|&(n, own)| (n, !own));
    nodes.dedup_by_key(|e| e.0);
    if let Some(before) = around {
        nodes.retain(|(n, _)| before.binary_search(n).is_err());
    }
    let world = |n: usize| {
        let [i, j, k] = phi.coords(n);
        phi.world(i, j, k)
    };
    let (own, face): (Vec<_>, Vec<_>) = nodes.into_iter().partition(|e| e.1);
    let points: Vec<Point3<f64>> = own.iter().map(|e| world(e.0)).collect();
    let projected = project_to_zero_level(previous_phi, &points, projection)
        .into_iter()
        .zip(own)
        .filter(|(p, _)| p.converged)
        .map(|(p, (node, _))| Misread {
            node,
            point: p.point,
            normal: outward_normal(previous_phi, &p.point),
        });
    // A face's corner: the point its own value places on S_{i−1}, |φ_{i−1}| away along its
    // normal, with that normal, so that the sample's plane gives the node exactly its value
    // (see the module doc).
    let placed = face.into_iter().filter_map(|(node, _)| {
        let x = world(node);
        let normal = unit_normal(previous_phi, &x)?;
        Some(Misread {
            node,
            point: x - truth[node] as f64 * normal,
            normal,
        })
    });
    projected.chain(placed).collect()
}

/// The marching cubes' reading of a face from its corner values in cyclic order (the asymptotic
/// decider, as [`crate::levelset::marching_cubes`] decides it): `None` when the face is not
/// ambiguous, else whether its inside corners are joined across it.
fn face_joined(v: [f32; 4]) -> Option<bool> {
    let inside = v.map(|x| x < 0.0);
    if inside[0] != inside[2] || inside[1] != inside[3] || inside[0] == inside[1] {
        return None;
    }
    let v = v.map(f64::from);
    let (joined, apart) = if inside[0] {
        (v[0] * v[2], v[1] * v[3])
    } else {
        (v[1] * v[3], v[0] * v[2])
    };
    Some(joined > apart)
}

/// The nodes of `phi` within `reach` nodes (along each axis) of each of `nodes`.
fn nodes_near(phi: &Grid3, nodes: &[usize], reach: i64) -> Vec<usize> {
    let dims = phi.dims().map(|d| d as i64);
    let mut out = Vec::new();
    for &n in nodes {
        let c = phi.coords(n).map(|v| v as i64);
        for z in c[2] - reach..=c[2] + reach {
            for y in c[1] - reach..=c[1] + reach {
                for x in c[0] - reach..=c[0] + reach {
                    if x >= 0 && y >= 0 && z >= 0 && x < dims[0] && y < dims[1] && z < dims[2] {
                        out.push((x + dims[0] * (y + dims[1] * z)) as usize);
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GridTransform;
    use crate::levelset::marching_cubes::{extract_surface, ExtractOptions};
    use crate::mesh::topology::connected_components;

    /// The face decider agrees with the marching cubes: on a 2×2×2 grid whose upper layer is
    /// outside, the lower face's two inside corners make one component when joined, two apart.
    #[test]
    fn face_joined_decides_as_the_marching_cubes() {
        let h = 1.0;
        let cases: [[f32; 4]; 6] = [
            [-0.4, 0.1, -0.4, 0.1],
            [-0.1, 0.4, -0.1, 0.4],
            [0.3, -0.2, 0.3, -0.25],
            [0.2, -0.3, 0.25, -0.3],
            [-0.3, 0.31, -0.3, 0.29],
            [-0.2, 0.2, -0.2, 0.2],
        ];
        for v in cases {
            let mut g =
                Grid3::new([2, 2, 2], GridTransform::new(Point3::origin(), h), 1.0).unwrap();
            for (c, (i, j)) in [(0, 0), (1, 0), (1, 1), (0, 1)].into_iter().enumerate() {
                g.set(i, j, 0, v[c]);
            }
            let mesh = extract_surface(&g, &ExtractOptions::default()).unwrap();
            let (components, _) = connected_components(&mesh);
            let joined = face_joined(v).expect("ambiguous");
            assert_eq!(joined, components == 1, "{v:?}: {components} components");
        }
        assert_eq!(face_joined([-0.1, -0.1, 0.2, 0.2]), None);
        assert_eq!(face_joined([-0.1, 0.1, 0.2, 0.2]), None);
    }
}
