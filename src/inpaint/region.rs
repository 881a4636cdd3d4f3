//! Regions D to inpaint: balls in world (file) units.

use nalgebra::Point3;

/// A ball of the damaged region D, in world (file) units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ball {
    /// Centre, world units.
    pub center: Point3<f64>,
    /// Radius, world units.
    pub radius: f64,
}

impl Ball {
    /// Whether `p` lies in the closed ball.
    pub fn contains(&self, p: &Point3<f64>) -> bool {
        (p - self.center).norm_squared() <= self.radius * self.radius
    }
}
