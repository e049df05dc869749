//! Fuzz target: the quadratic solver in f64 on arbitrary bit patterns, and the batch solver
//! against it (see `nlrt_tests::fuzz_input::fuzz_quadratic`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| nlrt_tests::fuzz_input::fuzz_quadratic::<f64>(data));
