//! Orientation repair: make the triangles of each component consistently wound, and outward.
