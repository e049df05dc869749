//! Fuzz target: nonlinear ray vs microtriangle in f64 on arbitrary bit patterns (see
//! `nlrt_tests::fuzz_input::fuzz_microtriangle`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| nlrt_tests::fuzz_input::fuzz_microtriangle::<f64>(data));
