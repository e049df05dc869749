#![allow(clippy::neg_cmp_op_on_partial_ord)] // NaN-aware comparisons are deliberate
//! Helpers shared by the cross-crate tests and the fuzz targets (which replay the same
//! properties), so a property is written once.

pub mod fuzz_input;
pub mod geometry;
