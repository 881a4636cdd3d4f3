//! The intact wall inside D is known: where D was drawn around a hole, the fill acts only in
//! the hole's shadow (paper Algorithm 4 copies φ_0 wherever the data are known; D is only the
//! region that holds the unknown part).
//!
//! A hole's ball (`holes`) is wider than the hole, so it also holds intact wall around the hole.
//! The fill of D (a tube along the centreline, a flow) matches that wall only roughly, and its
//! union with the input would push that wall out wherever the fill is wider: on real vessels the
//! largest errors of a chop's repair lay there, several voxels out on wall the input had right.
//! So at a node of such a ball where the fill adds volume, the nearest point q of the input's own
//! triangles (the cap triangles `cap_holes` added left out) is found: a node on the outer side of
//! the wall at q, with q farther than [`RIM_REACH_VOXELS`] from the hole's rim (the cap's
//! boundary), lies over intact wall, and the fill's weight there is 0; it rises by a cubic
//! smoothstep to its full value at the rim. Nodes over the hole (whose nearest wall is the rim)
//! and nodes behind the wall (in the lumen) keep the full weight. Balls with no cap triangle in
//! them (a narrowing, an occlusion given as a region of a closed mesh) keep the full weight:
//! their wall is the damage. So do the balls of an intact, only narrowed lumen whatever caps
//! they hold: a narrowing's region that reaches an open vessel end holds that end's cap, but
//! its wall is still the damage (the left iliac's stenosis 3 radii from its cut end, seed 26 of
//! `benches/repair_real`, was left as narrow as it came, 7.3h / −33% in D).
//!
//! Nor is a hole's cap known wall: it is this project's guess that closes the input for its
//! signed distance. Across a hole at a bifurcation's crotch the cap spans the space between the
//! branches, outside the vessel, and the union of the fill with the capped input kept that web
//! (the capped aorta's chop over the carina in seed 27 of `benches/repair_real`: the crotch
//! closed 6.6 mm below the truth's carina, 12.3h / +15% in D; now 9.6h / +10%). So [`cap_only_nodes`] finds the
//! nodes of a hole's ball that the capped input holds only by its cap: inside φ_0, but on the
//! outer side of the input's own wall at its nearest point; the fill alone decides there.

use super::region::Ball;
use crate::bvh::{bound_by_triangle, MeshBvh};
use crate::grid::Grid3;
use crate::TriMesh;
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use std::collections::HashMap;
use std::ops::Range;

/// Distance from the rim over which the fill's weight falls to 0 on the intact wall, voxels.
pub const RIM_REACH_VOXELS: f64 = 3.0;

/// The holes of D and the input's own wall around them, which [`keep_known_wall`] and
/// [`cap_only_nodes`] read: the holes' rims in D, which balls hold one, and the input's own
/// triangles (the capped input without its caps) with their hierarchy.
pub struct HoleWall {
    rim: Vec<(Point3<f64>, Point3<f64>)>,
    hole_ball: Vec<bool>,
    wall: OwnWall,
}

impl HoleWall {
    /// The holes of `closed` (the capped input, `cap_faces` its cap triangles) in `balls`;
    /// `intact` says per ball whether its lumen is intact, only narrowed (missing entries: no),
    /// which makes it no hole's. None when no hole's rim lies in D (a narrowing, an occlusion
    /// given as a region of a closed mesh): the wall in D is then the damage.
    pub fn new(
        closed: &TriMesh,
        cap_faces: Range<usize>,
        balls: &[Ball],
        intact: &[bool],
    ) -> Option<HoleWall> {
        let rim = hole_rims(closed, cap_faces.clone(), balls);
        if rim.is_empty() {
            return None;
        }
        let hole_ball = hole_balls(&rim, balls, intact);
        Some(HoleWall {
            rim,
            hole_ball,
            wall: OwnWall::new(closed, cap_faces),
        })
    }
}

/// Lowers `weights` (the fill's blend weight per node of `phi0`'s grid) over the intact wall of
/// D's hole balls (`holes`; see the module docs), at the nodes where the fill `psi` lies below
/// the input `phi0`; `h` is the voxel (world units). Returns the number of nodes whose weight was
/// lowered.
pub fn keep_known_wall(
    holes: &HoleWall,
    balls: &[Ball],
    phi0: &Grid3,
    psi: &Grid3,
    weights: &mut [f32],
    h: f64,
) -> usize {
    let HoleWall {
        rim,
        hole_ball,
        wall,
    } = holes;
    let reach = RIM_REACH_VOXELS * h;
    let [nx, ny, _] = phi0.dims();
    let t = *phi0.transform();
    weights
        .par_chunks_mut(nx * ny)
        .zip(phi0.data().par_chunks(nx * ny))
        .zip(psi.data().par_chunks(nx * ny))
        .enumerate()
        .map(|(k, ((w, known), fill))| {
            let mut n = 0;
            let mut hint: Option<u32> = None;
            for (i, w) in w.iter_mut().enumerate() {
                // Inside the input, or outside the fill, beyond the voxel next to the surface, the
                // union's sign is the same whatever the weight: nothing to keep.
                let band = h as f32;
                if *w <= 0.0 || fill[i] >= known[i] || known[i] < -band || fill[i] > band {
                    continue;
                }
                let p = t.index_to_world(Vector3::new((i % nx) as f64, (i / nx) as f64, k as f64));
                // Only in hole balls: a node also in a ball without a cap keeps its weight.
                if hole_ball_of(balls, hole_ball, &p).is_none() {
                    continue;
                }
                let Some((q, outer)) = wall.nearest(&p, &mut hint) else {
                    continue;
                };
                // Behind the wall (in the lumen): the fill adds nothing the input has wrong.
                if !outer {
                    continue;
                }
                let r = rim
                    .iter()
                    .map(|(a, b)| distance_to_segment(&q, a, b))
                    .fold(f64::INFINITY, f64::min);
                let s = (1.0 - r / reach).clamp(0.0, 1.0) as f32;
                let keep = s * s * (3.0 - 2.0 * s);
                if keep < 1.0 {
                    *w *= keep;
                    n += 1;
                }
            }
            n
        })
        .sum()
}

/// The nodes of `phi0`'s grid (the capped input's signed distance) in D's hole balls (`holes`)
/// that the input holds only by its holes' caps (see the module docs): inside `phi0`, outside or
/// within one of the grid's voxels of the fill `psi`'s surface and shallower in it than in
/// `phi0` (deeper fill nodes do not move the surface whatever the union gives them), and on the
/// outer side of the input's own wall at its nearest point. Returns the mask and, per ball, the
/// volume of the cells of these nodes where the fill is outside: what the capped input holds in
/// the ball that the union no longer keeps (world units³; a node counts in the first hole ball
/// holding it).
pub fn cap_only_nodes(
    holes: &HoleWall,
    balls: &[Ball],
    phi0: &Grid3,
    psi: &Grid3,
) -> (Vec<bool>, Vec<f64>) {
    let mut mask = vec![false; phi0.data().len()];
    let mut volumes = vec![0.0; balls.len()];
    let voxel = phi0.voxel();
    let band = voxel as f32;
    let [nx, ny, _] = phi0.dims();
    let t = *phi0.transform();
    let per_slab: Vec<Vec<(usize, f64)>> = mask
        .par_chunks_mut(nx * ny)
        .zip(phi0.data().par_chunks(nx * ny))
        .zip(psi.data().par_chunks(nx * ny))
        .enumerate()
        .map(|(k, ((m, known), fill))| {
            let mut outside = Vec::new();
            let mut hint: Option<u32> = None;
            for (i, m) in m.iter_mut().enumerate() {
                if known[i] >= 0.0 || fill[i] <= known[i] || fill[i] < -band {
                    continue;
                }
                let p = t.index_to_world(Vector3::new((i % nx) as f64, (i / nx) as f64, k as f64));
                let Some(ball) = hole_ball_of(balls, &holes.hole_ball, &p) else {
                    continue;
                };
                if let Some((_, true)) = holes.wall.nearest(&p, &mut hint) {
                    *m = true;
                    if fill[i] > 0.0 {
                        outside.push((ball, voxel.powi(3)));
                    }
                }
            }
            outside
        })
        .collect();
    for (ball, v) in per_slab.into_iter().flatten() {
        volumes[ball] += v;
    }
    (mask, volumes)
}

/// The input's own triangles (the capped input without its cap triangles) and their hierarchy.
struct OwnWall {
    mesh: TriMesh,
    bvh: MeshBvh,
}

impl OwnWall {
    fn new(closed: &TriMesh, cap_faces: Range<usize>) -> Self {
        let faces: Vec<[u32; 3]> = closed
            .faces
            .iter()
            .enumerate()
            .filter(|(i, _)| !cap_faces.contains(i))
            .map(|(_, f)| *f)
            .collect();
        let mesh = TriMesh::new(closed.vertices.clone(), faces);
        let bvh = MeshBvh::new(&mesh);
        OwnWall { mesh, bvh }
    }

    /// The wall's nearest point to `p` and whether `p` lies on the wall's outer side there. The
    /// query is bounded by the distance to `hint`'s triangle, the previous node's nearest (the
    /// same answer, found opening far fewer boxes: neighbouring nodes share their walls), and
    /// `hint` becomes this one's.
    fn nearest(&self, p: &Point3<f64>, hint: &mut Option<u32>) -> Option<(Point3<f64>, bool)> {
        let bound = hint.map(|f| bound_by_triangle(p, &self.mesh.triangle(f as usize)));
        let q = self.bvh.closest_point_bounded(p, bound);
        if !q.is_found() {
            return None;
        }
        *hint = Some(q.face);
        let outer = (p - q.point).dot(&self.mesh.face_normal_raw(q.face as usize)) > 0.0;
        Some((q.point, outer))
    }
}

/// The first of the hole balls (`hole_ball[k]`) that holds `p`; None when none does or when a
/// ball without a cap holds it too (its wall is the damage).
fn hole_ball_of(balls: &[Ball], hole_ball: &[bool], p: &Point3<f64>) -> Option<usize> {
    let mut first = None;
    for (k, (b, &hole)) in balls.iter().zip(hole_ball).enumerate() {
        if b.contains(p) {
            if !hole {
                return None;
            }
            first = first.or(Some(k));
        }
    }
    first
}

/// Per ball: whether it is a hole's, a segment of `rim` with an end in it and its lumen not
/// `intact` (only narrowed: a narrowing's region that reaches an open vessel end holds that end's
/// cap, but its wall is the damage; missing entries: not intact).
pub fn hole_balls(
    rim: &[(Point3<f64>, Point3<f64>)],
    balls: &[Ball],
    intact: &[bool],
) -> Vec<bool> {
    balls
        .iter()
        .enumerate()
        .map(|(i, ball)| {
            !intact.get(i).copied().unwrap_or(false)
                && rim
                    .iter()
                    .any(|(a, b)| ball.contains(a) || ball.contains(b))
        })
        .collect()
}

/// The end points of the segments of `rim`, each once (in the order first met).
pub fn rim_points(rim: &[(Point3<f64>, Point3<f64>)]) -> Vec<Point3<f64>> {
    let mut seen = std::collections::HashSet::new();
    rim.iter()
        .flat_map(|(a, b)| [*a, *b])
        .filter(|p| seen.insert([p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]))
        .collect()
}

/// The rims of the holes in `balls`: the edges that bound the cap triangles (used once by them),
/// with an end inside a ball, as segments.
pub fn hole_rims(
    closed: &TriMesh,
    cap_faces: Range<usize>,
    balls: &[Ball],
) -> Vec<(Point3<f64>, Point3<f64>)> {
    let mut uses: HashMap<(u32, u32), usize> = HashMap::new();
    for f in &closed.faces[cap_faces] {
        for e in 0..3 {
            let (a, b) = (f[e], f[(e + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut rim: Vec<(u32, u32)> = uses
        .into_iter()
        .filter(|&(_, n)| n == 1)
        .map(|(e, _)| e)
        .collect();
    // Hash order is random: sorted, so the rim (and every figure from it) is the same each run.
    rim.sort_unstable();
    rim.into_iter()
        .map(|(a, b)| (closed.vertices[a as usize], closed.vertices[b as usize]))
        .filter(|(a, b)| {
            balls
                .iter()
                .any(|ball| ball.contains(a) || ball.contains(b))
        })
        .collect()
}

/// Distance from `p` to the segment from `a` to `b`.
fn distance_to_segment(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let s = if len2 > 0.0 {
        ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * s)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Grid3, GridTransform};
    use crate::levelset::voxelize::{voxelize, VoxelizeOptions};
    use crate::mesh::cap::{cap_holes, CapOptions};
    use crate::mesh::primitives::open_tube;

    /// `mesh` without its triangles that have a corner in `chop`, its holes capped: the capped
    /// mesh and its cap triangles.
    fn chopped_and_capped(mesh: &TriMesh, chop: &Ball) -> (TriMesh, Range<usize>) {
        let faces = mesh
            .faces
            .iter()
            .filter(|f| !f.iter().any(|&v| chop.contains(&mesh.vertices[v as usize])))
            .copied()
            .collect();
        let (closed, report) = cap_holes(
            &TriMesh::new(mesh.vertices.clone(), faces),
            &CapOptions::default(),
        )
        .unwrap();
        (closed, report.cap_faces)
    }

    #[test]
    fn the_fill_is_kept_over_the_hole_and_dropped_over_the_intact_wall() {
        // A tube of radius 5 along z with a hole chopped in its wall at x = 5, capped; D a ball
        // of radius 8 around the hole; a fill 2 units wider than the input everywhere.
        let tube = open_tube(5.0, 40.0, 96, 121);
        let chop = Ball {
            center: Point3::new(5.0, 0.0, 20.0),
            radius: 3.0,
        };
        let (closed, cap_faces) = chopped_and_capped(&tube, &chop);
        let d = [Ball {
            center: chop.center,
            radius: 8.0,
        }];
        let h = 0.5;
        let t = GridTransform::new(Point3::new(-3.0, -8.0, 12.0), h);
        let phi0 = voxelize(&closed, [33, 33, 33], t, &VoxelizeOptions::default()).unwrap();
        let mut psi = phi0.clone();
        psi.data_mut().iter_mut().for_each(|v| *v -= 2.0);
        let mut w = vec![1.0f32; phi0.data().len()];
        let holes = HoleWall::new(&closed, cap_faces.clone(), &d, &[]).unwrap();
        let lowered = keep_known_wall(&holes, &d, &phi0, &psi, &mut w, h);
        assert!(lowered > 0);
        let at = |x: f64, y: f64, z: f64| {
            let i = ((x + 3.0) / h).round() as usize;
            let j = ((y + 8.0) / h).round() as usize;
            let k = ((z - 12.0) / h).round() as usize;
            w[i + 33 * (j + 33 * k)]
        };
        // Over the hole, between the cap and where the wall was: the fill acts in full.
        assert_eq!(at(4.5, 0.0, 20.0), 1.0);
        // Just outside the intact wall, a quarter turn from the hole: the input is kept.
        assert_eq!(at(0.0, 5.5, 20.0), 0.0);
        assert_eq!(at(5.5, 0.0, 26.0), 0.0);
        // In the lumen (behind the wall) nothing is lowered.
        assert_eq!(at(0.0, 3.0, 20.0), 1.0);
        // Without a cap in D (a narrowing of a closed mesh) there is no hole to keep a wall of.
        assert!(HoleWall::new(&closed, 0..0, &d, &[]).is_none());
        // Nor where the ball's lumen is intact, only narrowed, whatever caps it holds.
        let narrowed = HoleWall::new(&closed, cap_faces.clone(), &d, &[true]).unwrap();
        let mut w2 = vec![1.0f32; phi0.data().len()];
        assert_eq!(keep_known_wall(&narrowed, &d, &phi0, &psi, &mut w2, h), 0);
        assert!(w2.iter().all(|&v| v == 1.0));
    }

    #[test]
    fn a_cap_across_a_crotch_holds_space_outside_the_vessel_and_is_found() {
        use crate::inpaint::junction::smooth_min;
        use crate::levelset::marching_cubes::{extract_surface, ExtractOptions};
        // A bifurcation whose daughters part at 40°: a parent tube of radius 3 along z up to the
        // origin, daughters of radius 2.4 at ±20°, joined by a fillet; a hole chopped around its
        // carina. The cap across the hole spans the crotch, outside the vessel.
        let capsule = |p: &Point3<f64>, b: Vector3<f64>, r: f64| {
            let t = (p.coords.dot(&b) / b.norm_squared()).clamp(0.0, 1.0);
            (p.coords - b * t).norm() - r
        };
        let a = 20f64.to_radians();
        let d0 = Vector3::new(a.sin(), 0.0, a.cos()) * 20.0;
        let d1 = Vector3::new(-a.sin(), 0.0, a.cos()) * 20.0;
        let sdf = |p: &Point3<f64>| {
            let parent = capsule(&(p + Vector3::z() * 15.0), Vector3::z() * 15.0, 3.0);
            let body = smooth_min(
                smooth_min(parent, capsule(p, d0, 2.4), 1.5),
                capsule(p, d1, 2.4),
                1.5,
            );
            body.max(-p.z - 12.0).max(p.z - 14.0)
        };
        let h = 0.25;
        let t = GridTransform::new(Point3::new(-9.0, -5.0, -13.0), h);
        let mut g = Grid3::new([73, 41, 113], t, 0.0).unwrap();
        for n in 0..g.data().len() {
            let [i, j, k] = g.coords(n);
            let p = g.world(i, j, k);
            g.data_mut()[n] = sdf(&p) as f32;
        }
        let vessel = extract_surface(&g, &ExtractOptions::default()).unwrap();
        // The carina: where the body ends along +z between the daughters.
        let mut z = 0.0;
        while sdf(&Point3::new(0.0, 0.0, z)) < 0.0 {
            z += 0.01;
        }
        let chop = Ball {
            center: Point3::new(0.0, 0.0, z),
            radius: 3.5,
        };
        let (closed, cap_faces) = chopped_and_capped(&vessel, &chop);
        let d = [Ball {
            center: chop.center,
            radius: 5.0,
        }];
        let corner = chop.center - Vector3::repeat(5.5);
        let phi0 = voxelize(
            &closed,
            [45, 45, 45],
            GridTransform::new(corner, h),
            &VoxelizeOptions::default(),
        )
        .unwrap();
        // A fill that leaves everything out.
        let mut psi = phi0.clone();
        psi.data_mut().iter_mut().for_each(|v| *v = 1.0);
        let holes = HoleWall::new(&closed, cap_faces.clone(), &d, &[]).unwrap();
        let (mask, volumes) = cap_only_nodes(&holes, &d, &phi0, &psi);
        let node = |i: usize| {
            let [a, b, c] = phi0.coords(i);
            phi0.world(a, b, c)
        };
        let marked: Vec<Point3<f64>> = (0..mask.len()).filter(|&i| mask[i]).map(node).collect();
        // The crotch's web is found: nodes the capped input holds outside the vessel...
        let web = (0..mask.len())
            .filter(|&i| phi0.data()[i] < 0.0 && sdf(&node(i)) > h && d[0].contains(&node(i)))
            .count();
        assert!(web > 50, "the cap holds {web} nodes outside the vessel");
        assert!(
            marked.len() * 4 > web * 3,
            "{} of the {web} nodes outside the vessel found",
            marked.len()
        );
        // ...and nothing of the vessel's own lumen.
        for p in &marked {
            assert!(sdf(p) > -h, "{p} is {} inside", -sdf(p));
        }
        // The cells of the marked nodes, in the one ball.
        assert!((volumes[0] - marked.len() as f64 * h.powi(3)).abs() < 1e-9);
        // No cap in D, or a narrowed lumen's region: nothing.
        assert!(HoleWall::new(&closed, 0..0, &d, &[]).is_none());
        let narrowed = HoleWall::new(&closed, cap_faces, &d, &[true]).unwrap();
        let (none, v0) = cap_only_nodes(&narrowed, &d, &phi0, &psi);
        assert!(none.iter().all(|&m| !m) && v0 == vec![0.0]);
    }
}
