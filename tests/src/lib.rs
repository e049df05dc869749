//! Helpers shared by the cross-crate tests and the fuzz targets (which replay the same
//! properties), so a property is written once.

pub mod fuzz_input;
