//! Fuzz target: nonlinear ray vs microtriangle in f32 on arbitrary bit patterns (see
//! `nlrt_tests::fuzz_input::fuzz_microtriangle`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| nlrt_tests::fuzz_input::fuzz_microtriangle::<f32>(data));
