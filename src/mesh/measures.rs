//! Geometric measures of a triangle mesh: area, signed enclosed volume (divergence theorem),
//! bounding box, mean edge length, degenerate triangles, Euler characteristic and genus.
