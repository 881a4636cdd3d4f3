//! Bounding volume hierarchy queries on a triangle mesh.
