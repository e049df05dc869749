//! Fuzz target: the displacement traversal in f64 on arbitrary inputs (see
//! `nlrt_tests::fuzz_input::fuzz_displacement`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| nlrt_tests::fuzz_input::fuzz_displacement::<f64>(data));
