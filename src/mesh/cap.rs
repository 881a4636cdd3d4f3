//! Capping of boundary loops (open vessel ends and holes) with constrained Delaunay triangulations.
