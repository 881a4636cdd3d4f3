//! Stenosis and inpainted-volume measures of a repaired vessel.
