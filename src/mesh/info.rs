//! The `info` summary of a mesh (validation and measures), serialisable to JSON.
