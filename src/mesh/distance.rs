//! Surface-to-surface distances for `compare`.
