//! Synthetic damaged vessels with known ground truth.
