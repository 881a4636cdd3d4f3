//! The triangle hierarchy shared by every query: a binary BVH built by obvhs (PLOC with
//! reinsertion and SAH leaf collapse) over the mesh's triangles, plus an f64 copy of those
//! triangles in the hierarchy's leaf order.
//!
//! obvhs works in f32. Its node boxes are therefore only used to cull: every distance, ray
//! parameter and solid angle reported to the caller is computed in f64 from the f64 triangles.
//! To make sure f32 rounding can never cull the true answer, the boxes are made conservative:
//! they are stored relative to the centre of the mesh's bounding box (so f32 keeps its relative
//! precision even for meshes far from the origin), each triangle's box is widened by
//! [`MeshBvh::padding`] (a fixed fraction of the bounding-box diagonal) and its corners are
//! rounded outward (down for minima, up for maxima) when converted to f32. The builder only
//! takes unions of these boxes, which is exact, so every node box contains its triangles with
//! that margin to spare.

use glam::Vec3A;
use nalgebra::{Point3, Vector3};
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::bvh2::Bvh2;
use obvhs::BvhBuildParams;

use crate::TriMesh;

/// Box padding as a fraction of the mesh's bounding-box diagonal. f32 rounding of the local
/// coordinates, of a ray and of obvhs's slab test stays below ~1e-6 of the diagonal, so this
/// leaves an order of magnitude to spare while costing nothing measurable in culling.
const PAD_FRACTION: f64 = 1e-5;

/// Largest number of triangles in a leaf (obvhs collapses leaves by its SAH cost up to this).
const MAX_LEAF_TRIANGLES: u32 = 4;

/// A bounding volume hierarchy over the triangles of a mesh, for closest-point queries
/// ([`MeshBvh::closest_point`]), ray casts ([`MeshBvh::cast_ray`]) and, through
/// [`crate::bvh::WindingNumber`], the fast winding number.
///
/// The mesh is copied (as f64 triangles), so the hierarchy does not borrow it. Triangles with a
/// vertex index out of range or a non-finite coordinate are left out of the hierarchy: no query
/// ever reports them.
#[derive(Clone)]
pub struct MeshBvh {
    /// The obvhs hierarchy; node boxes are in the local frame (world − `origin`), padded.
    pub(crate) bvh: Bvh2,
    /// Triangles in leaf order (`bvh` leaf slot k ↔ `tris[k]`), world coordinates.
    pub(crate) tris: Vec<[Point3<f64>; 3]>,
    /// Mesh face index of each entry of `tris`.
    pub(crate) face_ids: Vec<u32>,
    /// Origin of the local frame of the f32 boxes (centre of the bounding box).
    pub(crate) origin: Vector3<f64>,
    /// Padding of every box, world units.
    pub(crate) pad: f64,
    /// Bounding box of the indexed triangles (world units); both corners are NaN when empty.
    pub(crate) bbox: [Point3<f64>; 2],
}

impl std::fmt::Debug for MeshBvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MeshBvh")
            .field("triangles", &self.tris.len())
            .field("nodes", &self.bvh.nodes.len())
            .field("bbox", &self.bbox)
            .finish()
    }
}

/// Largest f32 that is ≤ `x` (outward rounding of a box minimum).
pub(crate) fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x {
        f.next_down()
    } else {
        f
    }
}

/// Smallest f32 that is ≥ `x` (outward rounding of a box maximum).
pub(crate) fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x {
        f.next_up()
    } else {
        f
    }
}

impl MeshBvh {
    /// Builds the hierarchy over the triangles of `mesh`.
    pub fn new(mesh: &TriMesh) -> Self {
        let nv = mesh.vertices.len();
        let mut tris = Vec::with_capacity(mesh.faces.len());
        let mut faces = Vec::with_capacity(mesh.faces.len());
        for (f, face) in mesh.faces.iter().enumerate() {
            if face.iter().any(|&i| i as usize >= nv) {
                continue;
            }
            let t = face.map(|i| mesh.vertices[i as usize]);
            if t.iter().all(|v| v.iter().all(|c| c.is_finite())) {
                tris.push(t);
                faces.push(f as u32);
            }
        }

        let nan = Point3::new(f64::NAN, f64::NAN, f64::NAN);
        if tris.is_empty() {
            return MeshBvh {
                bvh: Bvh2::default(),
                tris,
                face_ids: faces,
                origin: Vector3::zeros(),
                pad: 0.0,
                bbox: [nan, nan],
            };
        }

        let mut lo = Point3::from([f64::INFINITY; 3]);
        let mut hi = Point3::from([f64::NEG_INFINITY; 3]);
        for v in tris.iter().flatten() {
            lo = lo.inf(v);
            hi = hi.sup(v);
        }
        let origin = (lo.coords + hi.coords) * 0.5;
        let pad = PAD_FRACTION * (hi - lo).norm();

        let aabbs: Vec<Aabb> = tris
            .iter()
            .map(|t| {
                let mut bmin = [0f32; 3];
                let mut bmax = [0f32; 3];
                for k in 0..3 {
                    let l = t.map(|v| v[k] - origin[k]);
                    bmin[k] = f32_down(l[0].min(l[1]).min(l[2]) - pad);
                    bmax[k] = f32_up(l[0].max(l[1]).max(l[2]) + pad);
                }
                Aabb::new(Vec3A::from(bmin), Vec3A::from(bmax))
            })
            .collect();

        let params = BvhBuildParams {
            max_prims_per_leaf: MAX_LEAF_TRIANGLES,
            // Spatial splits would put a triangle in several leaves (double counting in the
            // winding number and the ray-hit counter).
            pre_split: false,
            // The fast build (less reinsertion than the medium one): a hierarchy here is built
            // for one command, often on 10⁵ triangles, and the medium build's slightly better
            // tree did not repay its build time (the aneurysm's narrowing repaired in 0.97 s
            // instead of 0.99 s, every figure of benches/repair_real the same).
            ..BvhBuildParams::fast_build()
        };
        let bvh = build_bvh2(&aabbs, params, &mut std::time::Duration::default());

        // Reorder the triangles into leaf order so a leaf reads a contiguous run.
        let tris_sorted = bvh
            .primitive_indices
            .iter()
            .map(|&i| tris[i as usize])
            .collect();
        let face_ids = bvh
            .primitive_indices
            .iter()
            .map(|&i| faces[i as usize])
            .collect();

        MeshBvh {
            bvh,
            tris: tris_sorted,
            face_ids,
            origin,
            pad,
            bbox: [lo, hi],
        }
    }

    /// Number of triangles in the hierarchy (faces with bad indices or coordinates excluded).
    pub fn num_triangles(&self) -> usize {
        self.tris.len()
    }

    /// Number of nodes of the binary hierarchy.
    pub fn num_nodes(&self) -> usize {
        self.bvh.nodes.len()
    }

    /// Whether the hierarchy holds no triangle (every query then finds nothing).
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// Bounding box `[min, max]` of the indexed triangles (world units); `None` when empty.
    pub fn bounding_box(&self) -> Option<[Point3<f64>; 2]> {
        (!self.is_empty()).then_some(self.bbox)
    }

    /// Margin by which every node box exceeds the triangles it holds (world units).
    pub fn padding(&self) -> f64 {
        self.pad
    }

    /// The underlying obvhs hierarchy. Node boxes are relative to [`MeshBvh::local_origin`] and
    /// padded; leaf slot k holds triangle [`MeshBvh::slot_face`]`(k)`.
    pub fn obvhs_bvh(&self) -> &Bvh2 {
        &self.bvh
    }

    /// Origin of the local frame of the node boxes (world = local + origin).
    pub fn local_origin(&self) -> Vector3<f64> {
        self.origin
    }

    /// Mesh face index held in leaf slot `slot`.
    pub fn slot_face(&self, slot: usize) -> u32 {
        self.face_ids[slot]
    }

    /// Triangle corners held in leaf slot `slot` (world units, f64).
    pub fn slot_triangle(&self, slot: usize) -> &[Point3<f64>; 3] {
        &self.tris[slot]
    }

    /// Node box `node` in the local frame, as f64 (exact conversion; includes the padding).
    pub(crate) fn node_box_local(&self, node: usize) -> ([f64; 3], [f64; 3]) {
        let b = self.bvh.nodes[node].aabb();
        (
            [b.min.x as f64, b.min.y as f64, b.min.z as f64],
            [b.max.x as f64, b.max.y as f64, b.max.z as f64],
        )
    }
}
