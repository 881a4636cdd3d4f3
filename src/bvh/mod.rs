//! Bounding volume hierarchy queries on a triangle mesh: closest point (branch and bound),
//! ray casts (watertight, Woop et al. 2013) and the fast generalized winding number (Barill et
//! al. 2018), on an obvhs BVH2 with every final value computed in f64; plus brute-force
//! references for testing.

pub mod brute;
mod closest;
mod ray;
mod tri_bvh;
mod winding;

pub use closest::{bound_by_triangle, closest_point_on_triangle, ClosestPoint, TrianglePoints};
pub use ray::{intersect_ray_triangle, RayHit};
pub use tri_bvh::MeshBvh;
pub use winding::{solid_angle, WindingNumber, WindingOptions};
